// The neural fur field (engine/fur/fur_field.*) and what the fur stage builds on it: the warm start's
// strand everywhere, training forward against chunked inference, the whole chain's adjoint against
// finite differences, root subsets, the streamed .hair writer, the baseline groom. The head kernel's
// gradients are in the gradcheck catalog (test_gradcheck).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <set>

#include "engine/core/error.hpp"
#include "engine/fur/baseline_groom.hpp"
#include "engine/fur/fur_field.hpp"
#include "engine/fur/fur_trainer.hpp"
#include "engine/io/strand_files.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;
namespace fs = std::filesystem;

namespace {

// `n` roots scattered in a box with random orthonormal frames, lengths from 1e-2 to 2e-2.
Roots random_roots(std::uint32_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  Roots r;
  for (std::uint32_t i = 0; i < n; ++i) {
    const glm::vec3 nrm = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    glm::vec3 t(u(rng), u(rng), u(rng));
    t = glm::normalize(t - glm::dot(t, nrm) * nrm);
    r.face.push_back(0);
    r.barycentric.push_back(glm::vec3(1.f / 3.f));
    r.position.push_back(glm::vec3(u(rng), u(rng), 0.5f * u(rng)));
    r.tangent.push_back(t);
    r.bitangent.push_back(glm::cross(nrm, t));
    r.normal.push_back(nrm);
    r.direction.push_back(t);
    r.region.push_back(3);
    r.length.push_back(0.015f + 0.005f * u(rng));
  }
  return r;
}

std::vector<std::uint32_t> all_ids(std::size_t n) {
  std::vector<std::uint32_t> ids(n);
  for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
  return ids;
}

std::vector<float> infer_all(FurField& field, const Roots& roots, std::uint32_t chunk) {
  std::vector<float> out;
  field.infer(roots, all_ids(roots.size()), chunk,
              [&](std::size_t, std::uint32_t, const std::vector<float>& points, const std::vector<float>&) { out.insert(out.end(), points.begin(), points.end()); });
  return out;
}

glm::vec3 point(const std::vector<float>& p, std::size_t strand, std::size_t k) {
  const std::size_t i = (strand * kStrandPoints + k) * 3;
  return {p[i], p[i + 1], p[i + 2]};
}

}  // namespace

TEST_CASE("fur field: the warm start puts the lifted straight strand of the root's length at every root") {
  gpu::Context& ctx = test::context();
  std::unique_ptr<StrandPrior> prior = shipped_strand_prior(ctx);
  const Roots roots = random_roots(9, 3);
  FurField field(ctx, {}, *prior, root_box(roots), 5);
  const double angle = 25.0;
  field.start_at(lifted_strand_latent(*prior, angle), 0.5413f, 0.f);  // weight scale 0: the same latent everywhere
  const std::vector<float> points = infer_all(field, roots, 4);
  REQUIRE(points.size() == roots.size() * kStrandPoints * 3);
  const float a = float(angle * M_PI / 180.0);
  for (std::size_t s = 0; s < roots.size(); ++s) {
    CHECK(glm::length(point(points, s, 0) - roots.position[s]) < 1e-6f);
    float arc = 0;
    for (std::size_t k = 1; k < kStrandPoints; ++k) arc += glm::length(point(points, s, k) - point(points, s, k - 1));
    CHECK(arc == doctest::Approx(roots.length[s]).epsilon(1e-3));
    const glm::vec3 heading = glm::normalize(point(points, s, kStrandSegments) - roots.position[s]);
    const glm::vec3 expected = std::cos(a) * roots.tangent[s] + std::sin(a) * roots.normal[s];
    CHECK(std::acos(std::min(1.f, glm::dot(heading, expected))) * 180.f / float(M_PI) < 3.f);  // the prior's fit of a straight line
  }
}

TEST_CASE("fur field: the training forward gives the points of chunked inference, whatever the chunk") {
  gpu::Context& ctx = test::context();
  std::unique_ptr<StrandPrior> prior = shipped_strand_prior(ctx);
  const Roots roots = random_roots(13, 7);
  FurField field(ctx, {}, *prior, root_box(roots), 2);
  FurField::Batch batch(field, 13);
  std::vector<float> normalised, frames;
  strand_inputs(roots, all_ids(13), field.box(), normalised, frames);
  batch.roots.upload(normalised);
  batch.frames.upload(frames);
  gpu::Stream stream(ctx);
  field.forward(stream, batch);
  stream.submit_and_wait();
  const std::vector<float> trained = batch.points.download();
  for (std::uint32_t chunk : {1u, 5u, 13u, 100u}) {
    const std::vector<float> inferred = infer_all(field, roots, chunk);
    REQUIRE(inferred.size() == trained.size());
    float worst = 0;
    for (std::size_t i = 0; i < trained.size(); ++i) {
      REQUIRE(std::isfinite(inferred[i]));
      worst = std::max(worst, std::abs(inferred[i] - trained[i]));
    }
    CHECK(worst < 1e-5f);
  }
}

TEST_CASE("fur field: the adjoint through head, decoder, geometry and MLP matches finite differences of the parameters") {
  gpu::Context& ctx = test::context();
  std::unique_ptr<StrandPrior> prior = shipped_strand_prior(ctx);
  const Roots roots = random_roots(6, 11);
  FurField field(ctx, {}, *prior, root_box(roots), 9);
  FurField::Batch batch(field, 6);
  std::vector<float> normalised, frames;
  strand_inputs(roots, all_ids(6), field.box(), normalised, frames);
  batch.roots.upload(normalised);
  batch.frames.upload(frames);
  // Loss = g . points + h . confidence with fixed random g, h.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> g(batch.points.size()), h(batch.confidence.size());
  for (float& v : g) v = u(rng);
  for (float& v : h) v = u(rng);
  const auto loss = [&] {
    gpu::Stream s(ctx);
    field.forward(s, batch);
    s.submit_and_wait();
    const std::vector<float> p = batch.points.download(), c = batch.confidence.download();
    double sum = 0;
    for (std::size_t i = 0; i < p.size(); ++i) sum += double(g[i]) * p[i];
    for (std::size_t i = 0; i < c.size(); ++i) sum += double(h[i]) * c[i];
    return sum;
  };
  loss();
  batch.grad_points.upload(g);
  batch.grad_confidence.upload(h);
  {
    gpu::Stream s(ctx);
    field.backward(s, batch);
    s.submit_and_wait();
  }
  const std::vector<float> grads = field.mlp().gradients().download();
  std::vector<float> params = field.parameters();
  // The last layer's biases (latent and confidence) and weights of the first and last layers.
  const nn::LayerShape& first = field.mlp().layers().front();
  const nn::LayerShape& last = field.mlp().layers().back();
  std::vector<std::uint64_t> probe{last.bias_offset, last.bias_offset + 17, last.bias_offset + 64, last.weight_offset + 5,
                                   first.weight_offset + 2, first.weight_offset + 40, first.bias_offset + 3};
  int compared = 0;
  for (std::uint64_t i : probe) {
    const float h_step = 1e-2f * std::max(1.f, std::abs(params[i]));
    const float saved = params[i];
    params[i] = saved + h_step;
    field.set_parameters(params);
    const double up = loss();
    params[i] = saved - h_step;
    field.set_parameters(params);
    const double down = loss();
    params[i] = saved;
    field.set_parameters(params);
    const double fd = (up - down) / (2.0 * h_step);
    INFO("parameter " << i << ": adjoint " << grads[i] << ", finite difference " << fd);
    REQUIRE(std::isfinite(grads[i]));
    if (std::abs(fd) < 1e-4) {  // a dead ReLU path: both must be (near) zero
      CHECK(std::abs(grads[i]) < 1e-3);
      continue;
    }
    // A wiring check: every kernel's own adjoint is exact in the gradcheck catalog; here a missing or
    // doubled term would be off by 100 % or more, while float differences across ReLU kinks of the
    // deeper layers stay within 20 %.
    CHECK(std::abs(double(grads[i]) - fd) <= 0.2 * std::abs(fd) + 1e-4);
    ++compared;
  }
  CHECK(compared >= 4);
}

TEST_CASE("fur: root subsets are distinct, in range, a function of the seed, and all roots when asked for more") {
  const std::vector<std::uint32_t> a = sample_indices(100000, 15000, 42), b = sample_indices(100000, 15000, 42);
  CHECK(a == b);
  CHECK(sample_indices(100000, 15000, 43) != a);
  std::set<std::uint32_t> unique(a.begin(), a.end());
  CHECK(unique.size() == a.size());
  CHECK(*unique.rbegin() < 100000u);
  CHECK(sample_indices(10, 15000, 1).size() == 10);
  CHECK(sample_indices(0, 5, 1).empty());
}

TEST_CASE("io: a streamed .hair file reads back strand by strand; a NaN or a wrong count writes nothing") {
  const fs::path dir = fs::temp_directory_path() / "nf_test_uniform_hair";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<float> xyz(7 * 4 * 3);
  for (std::size_t i = 0; i < xyz.size(); ++i) xyz[i] = float(i) * 0.5f;
  io::write_uniform_hair(dir / "a.hair", 7, 4, [&](const auto& write) {
    write(std::span<const float>(xyz).subspan(0, 5));  // chunks need not align with strands
    write(std::span<const float>(xyz).subspan(5));
  });
  const io::StrandSet back = io::read_hair(dir / "a.hair");
  CHECK(back.strand_count() == 7);
  CHECK(back.points == xyz);
  xyz[30] = NAN;
  CHECK_THROWS_AS(io::write_uniform_hair(dir / "b.hair", 7, 4, [&](const auto& write) { write(std::span<const float>(xyz)); }), InputError);
  CHECK_FALSE(fs::exists(dir / "b.hair"));
  CHECK_THROWS_AS(io::write_uniform_hair(dir / "c.hair", 8, 4, [&](const auto& write) { write(std::span<const float>(xyz).subspan(0, 12)); }),
                  InternalError);
  CHECK_FALSE(fs::exists(dir / "c.hair"));
  io::write_uniform_hair(dir / "empty.hair", 0, 100, [](const auto&) {});
  CHECK(io::read_hair(dir / "empty.hair").strand_count() == 0);
  fs::remove_all(dir);
}

TEST_CASE("fur: the baseline groom is straight, of the root's length, along the projected growth direction, lifted by the angle") {
  Roots roots = random_roots(5, 21);
  roots.direction[2] = roots.normal[2];  // a direction along the normal: falls back to the tangent
  const io::StrandSet set = baseline_groom(roots, {0, 2, 4}, 30.0, 10);
  REQUIRE(set.strand_count() == 3);
  const float a = float(30.0 * M_PI / 180.0);
  for (std::uint32_t s = 0; s < 3; ++s) {
    const std::uint32_t r = std::array<std::uint32_t, 3>{0, 2, 4}[s];
    const glm::vec3 root(set.points[set.offsets[s] * 3], set.points[set.offsets[s] * 3 + 1], set.points[set.offsets[s] * 3 + 2]);
    const std::size_t t = (set.offsets[s + 1] - 1) * 3;
    const glm::vec3 tip(set.points[t], set.points[t + 1], set.points[t + 2]);
    CHECK(glm::length(root - roots.position[r]) < 1e-6f);
    CHECK(glm::length(tip - root) == doctest::Approx(roots.length[r]).epsilon(1e-5));
    CHECK(glm::dot(glm::normalize(tip - root), roots.normal[r]) == doctest::Approx(std::sin(a)).epsilon(1e-4));
    CHECK(glm::dot(glm::normalize(tip - root), roots.tangent[r]) == doctest::Approx(std::cos(a)).epsilon(1e-4));
    CHECK(set.regions[s] == 3);
  }
}
