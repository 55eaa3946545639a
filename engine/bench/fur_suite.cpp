#include "engine/bench/fur_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <random>

#include <glm/glm.hpp>

#include "engine/bench/fur_scene_suite.hpp"
#include "engine/bench/record.hpp"
#include "engine/fur/strand_chamfer.hpp"
#include "engine/fur/strand_geometry.hpp"
#include "engine/fur/strand_losses.hpp"
#include "engine/gpu/buffer.hpp"

namespace nf::bench {
namespace {

constexpr const char* kSuite = "fur";

// Strands like a decoder's on a sphere of radius 0.5: rows of 99 segments (stride 300) and frames.
struct Batch {
  std::vector<float> rows, frames;
};

Batch make_batch(std::uint32_t strands, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.f, 1.f);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  Batch b;
  b.rows.assign(std::size_t(strands) * 300, 0.f);
  for (std::uint32_t s = 0; s < strands; ++s) {
    for (std::uint32_t j = 0; j < 99; ++j) {
      b.rows[std::size_t(s) * 300 + 3 * j] = 0.007f + 0.003f * u(rng);
      b.rows[std::size_t(s) * 300 + 3 * j + 1] = 0.002f * u(rng);
      b.rows[std::size_t(s) * 300 + 3 * j + 2] = 0.004f + 0.002f * u(rng);
    }
    const glm::vec3 normal = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
    glm::vec3 t = glm::cross(normal, glm::vec3(0, 1, 0));
    if (glm::length(t) < 1e-3f) t = glm::vec3(1, 0, 0);
    t = glm::normalize(t);
    const glm::vec3 bt = glm::cross(normal, t), root = 0.5f * normal;
    b.frames.insert(b.frames.end(), {root.x, root.y, root.z, 0.03f, t.x, t.y, t.z, bt.x, bt.y, bt.z, normal.x, normal.y, normal.z});
  }
  return b;
}

double max_relative(const std::vector<float>& a, const std::vector<double>& b) {
  double scale = 0, worst = 0;
  for (double v : b) scale = std::max(scale, std::abs(v));
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(double(a[i]) - b[i]));
  return scale > 0 ? worst / scale : worst;
}

}  // namespace

json run_fur_suite(gpu::Context& ctx, const Options& options) {
  const std::uint32_t strands = options.quick ? 3000 : 15000;
  const int repeats = options.quick ? 3 : 7;
  json records = json::array();
  const Batch batch = make_batch(strands, 1);
  const fur::StrandGeometryShape shape{strands, 99, 300};

  // Strand geometry: decoder rows -> world points, and the adjoint.
  gpu::Buffer<float> rows(ctx, batch.rows, "rows"), frames(ctx, batch.frames, "frames");
  gpu::Buffer<float> points(ctx, std::uint64_t(strands) * 300, "points"), grad_points(ctx, std::uint64_t(strands) * 300, "grad points");
  gpu::Buffer<float> grad_rows(ctx, batch.rows.size(), "grad rows"), grad_frames(ctx, batch.frames.size(), "grad frames");
  {
    std::vector<float> ones(std::size_t(strands) * 300, 1e-3f);
    grad_points.upload(ones);
    const Timing t = time_repeats(repeats, nullptr, [&] {
      gpu::Stream stream(ctx);
      fur::strand_geometry_forward(stream, shape, rows, frames, points);
      fur::strand_geometry_backward(stream, shape, rows, frames, grad_points, grad_rows, grad_frames);
      stream.submit_and_wait();
      return -1.0;
    });
    std::vector<double> ref;
    fur::strand_geometry_forward_ref(std::vector<double>(batch.rows.begin(), batch.rows.end()),
                                     std::vector<double>(batch.frames.begin(), batch.frames.end()), shape, ref);
    const double error = max_relative(points.download(), ref);
    records.push_back(make_record(ctx, kSuite, "strand_geometry", {{"strands", strands}, {"points_per_strand", 100}}, t,
                                  {{"strands_per_second", double(strands) / t.median()}, {"max_rel_error_vs_double", error}}));
  }

  // The geometric losses on those strands, against a sphere's SDF.
  {
    fur::SdfGridRef grid{{33, 33, 33}, {-0.8, -0.8, -0.8}, 0.05};
    std::vector<float> sdf;
    for (int k = 0; k < 33; ++k)
      for (int j = 0; j < 33; ++j)
        for (int i = 0; i < 33; ++i) sdf.push_back(glm::length(glm::vec3(-0.8f + 0.05f * i, -0.8f + 0.05f * j, -0.8f + 0.05f * k)) - 0.5f);
    std::vector<float> guides, lengths(strands, 0.03f);
    for (std::uint32_t s = 0; s < strands; ++s) guides.insert(guides.end(), {0.f, -1.f, 0.f});
    gpu::Buffer<float> d_guides(ctx, guides, "guides"), d_lengths(ctx, lengths, "lengths"), d_sdf(ctx, sdf, "sdf");
    const fur::StrandLossShape lshape{strands, 100};
    const fur::StrandLossBatch lb{lshape, grid, points, d_guides, d_lengths, d_sdf};
    fur::StrandLossScratch scratch(ctx, lshape);
    std::array<double, 3> values{};
    const Timing t = time_repeats(repeats, nullptr, [&] {
      gpu::Stream stream(ctx);
      fur::strand_losses_forward(stream, lb, scratch);
      fur::strand_losses_backward(stream, lb, scratch, {}, grad_points, false);
      stream.submit_and_wait();
      values = fur::strand_loss_values(scratch, lshape);
      return -1.0;
    });
    const std::vector<float> p = points.download();
    const std::array<double, 3> ref = fur::strand_losses_ref<double>(std::vector<double>(p.begin(), p.end()), std::vector<double>(guides.begin(), guides.end()),
                                                                    std::vector<double>(lengths.begin(), lengths.end()), grid,
                                                                    std::vector<double>(sdf.begin(), sdf.end()), lshape);
    double error = 0;
    for (int k = 0; k < 3; ++k) error = std::max(error, std::abs(values[std::size_t(k)] - ref[std::size_t(k)]) / std::max(1e-30, std::abs(ref[std::size_t(k)])));
    records.push_back(make_record(ctx, kSuite, "strand_losses", {{"strands", strands}, {"points_per_strand", 100}}, t,
                                  {{"strands_per_second", double(strands) / t.median()}, {"max_rel_error_vs_double", error},
                                   {"direction", values[0]}, {"curvature", values[1]}, {"penetration", values[2]}}));
  }

  // The one-way chamfer: 20,000 samples on a sphere just outside the roots against every strand point.
  {
    const std::uint32_t queries = options.quick ? 4000 : 20000;
    std::mt19937 rng(3);
    std::normal_distribution<float> n(0.f, 1.f);
    std::vector<float> q;
    for (std::uint32_t k = 0; k < queries; ++k) {
      const glm::vec3 v = 0.52f * glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
      q.insert(q.end(), {v.x, v.y, v.z});
    }
    gpu::Buffer<float> d_queries(ctx, q, "queries");
    // The fur stage's choice of grid: the sphere's area, the batch's points, an eighth of the box.
    const fur::ChamferGrid grid = fur::chamfer_grid_for(glm::vec3(-0.7f), glm::vec3(0.7f), std::uint64_t(strands) * 100,
                                                        4.0 * 3.14159265358979 * 0.25, 1.4 / 8);
    fur::StrandChamferScratch scratch(ctx, std::uint64_t(strands) * 100, queries, grid);
    fur::ChamferValue value;
    const Timing t = time_repeats(repeats, nullptr, [&] {
      gpu::Stream stream(ctx);
      fur::strand_chamfer_forward(stream, grid, d_queries, points, scratch);
      fur::strand_chamfer_backward(stream, d_queries, points, scratch, 20.0, grad_points, false);
      stream.submit_and_wait();
      value = fur::strand_chamfer_value(scratch);
      return -1.0;
    });
    // Exactness on a sample of the queries against the brute force.
    const std::vector<float> p = points.download();
    const std::vector<std::uint32_t> nn = scratch.nearest.download();
    std::size_t checked = 0, wrong = 0;
    for (std::size_t k = 0; k < queries; k += 211, ++checked) {
      const std::vector<float> one(q.begin() + std::ptrdiff_t(3 * k), q.begin() + std::ptrdiff_t(3 * k + 3));
      wrong += fur::nearest_points_ref(one, p, grid.reach())[0] != nn[k];
    }
    records.push_back(make_record(ctx, kSuite, "strand_chamfer", {{"strand_points", std::uint64_t(strands) * 100}, {"queries", queries}, {"cells", grid.dims[0]}, {"rings", grid.max_rings}}, t,
                                  {{"queries_per_second", double(queries) / t.median()}, {"loss", value.loss},
                                   {"unmatched", value.unmatched}, {"sampled_queries", checked}, {"wrong_nearest", wrong}}));
  }
  // The stage on whole scenes (tens of minutes; NF_BENCH_FUR_SCENES=0: the kernels only).
  const char* scenes = std::getenv("NF_BENCH_FUR_SCENES");
  if (!scenes || std::string(scenes) != "0")
    for (json& r : run_fur_scene_suite(ctx, options)) records.push_back(std::move(r));
  return records;
}

}  // namespace nf::bench
