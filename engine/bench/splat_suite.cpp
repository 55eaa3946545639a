#include "engine/bench/splat_suite.hpp"

#include <cmath>

#include "engine/bench/core_suite.hpp"
#include "engine/bench/record.hpp"
#include "engine/body/quadruped.hpp"
#include "engine/core/progress.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/splat/rasterizer.hpp"
#include "engine/splat/rasterizer_ref.hpp"
#include "engine/synth/camera_rig.hpp"
#include "engine/synth/fur_growth.hpp"
#include "engine/synth/strand_renderer.hpp"

namespace nf::bench {
namespace {

constexpr const char* kSuite = "splat";

struct Scene {
  geometry::Mesh body;
  synth::Fur fur;
  float radius;
  glm::vec3 centre;
};

Scene make_scene(std::uint32_t strands, std::uint32_t points) {
  const auto p = body::animal_proportions("cat");
  Scene s;
  s.body = body::pose_body(body::build_quadruped(p, {p.torso_length / 80}), {});
  synth::GrowOptions o;
  o.strand_count = strands, o.points_per_strand = points, o.seed = 1, o.animal = "cat", o.torso_length = p.torso_length;
  s.fur = synth::grow_fur(s.body, knowledge::preset("cat"), synth::fur_style("cat"), o);
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (std::size_t i = 0; i + 2 < s.fur.strands.points.size(); i += 3) {
    const glm::vec3 q(s.fur.strands.points[i], s.fur.strands.points[i + 1], s.fur.strands.points[i + 2]);
    lo = glm::min(lo, q), hi = glm::max(hi, q);
  }
  s.centre = 0.5f * (lo + hi), s.radius = 0.5f * glm::length(hi - lo);
  return s;
}

}  // namespace

json run_splat_suite(gpu::Context& ctx, const Options& options) {
  const std::uint32_t strands = options.quick ? 2000 : 15000, points = options.quick ? 32 : 100;
  const int repeats = options.quick ? 2 : 3;
  const double fma = measure_fma_gflops(ctx, options.quick);
  const double traffic_roof = measure_copy_traffic_gbps(ctx, options.quick);
  const Scene scene = make_scene(strands, points);
  const splat::StrandShape shape{strands, points};
  const splat::RasterParams rp;  // the paper's width 0.0025 and length scale 0.5
  gpu::Buffer<float> d_points(ctx, scene.fur.strands.points, "bench strand points");
  gpu::Buffer<float> d_conf(ctx, std::vector<float>(shape.segments(), 1.0f), "bench confidence");
  gpu::Buffer<float> d_grad_points(ctx, shape.points() * 3, "bench grad points");
  gpu::Buffer<float> d_grad_conf(ctx, shape.segments(), "bench grad confidence");
  json records = json::array();
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> sizes =
      options.quick ? std::vector<std::pair<std::uint32_t, std::uint32_t>>{{128, 128}, {320, 180}}
                    : std::vector<std::pair<std::uint32_t, std::uint32_t>>{{512, 512}, {1920, 1080}};
  Progress progress("bench splat", sizes.size());
  std::uint64_t done = 0;
  for (const auto& [w, h] : sizes) {
    synth::RigOptions rig;
    rig.views = 1, rig.width = w, rig.height = h;
    const io::Camera cam = synth::camera_rings(scene.centre, scene.radius, glm::vec3(0, 1, 0), rig)[0];
    const splat::RasterCamera rc = splat::raster_camera(cam, 0.01, 20.0);
    const std::uint64_t pixels = std::uint64_t(w) * h;
    gpu::Buffer<float> image(ctx, pixels * splat::kChannels, "bench raster image");
    gpu::Buffer<float> grad_image(ctx, std::vector<float>(pixels * splat::kChannels, 1e-3f), "bench raster image gradient");
    splat::StrandRasterizer raster(ctx);

    ctx.reset_pass_totals();
    const Timing fwd = time_repeats(repeats, nullptr, [&] {
      raster.forward(shape, d_points, d_conf, rc, rp, {}, image);
      return -1.0;
    });
    const auto fwd_passes = pass_ms_per_run(ctx, repeats + 1);
    ctx.reset_pass_totals();
    const Timing both = time_repeats(repeats, nullptr, [&] {
      raster.forward(shape, d_points, d_conf, rc, rp, {}, image);
      gpu::Stream stream(ctx);
      raster.backward(stream, grad_image, d_grad_points, d_grad_conf, false);
      stream.submit_and_wait();
      return -1.0;
    });
    const auto both_passes = pass_ms_per_run(ctx, repeats + 1);

    // Error of the splatted silhouette against the ray-traced coverage of the same strands.
    synth::StrandLook look;
    look.radius = float(rp.gaussian.width);
    synth::RenderOptions ro;
    ro.samples_per_axis = options.quick ? 2 : 4, ro.render_points = points;
    const synth::StrandRenderer tracer(geometry::Mesh{}, {}, scene.fur.strands, look, ro);  // hair silhouette only
    const synth::Rendered truth = tracer.render(cam);
    const std::vector<float> img = image.download(0, pixels);
    double abs_err = 0, covered = 0, splatted = 0;
    for (std::uint64_t i = 0; i < pixels; ++i) {
      abs_err += std::fabs(img[i] - truth.coverage.pixels[i]);
      covered += truth.coverage.pixels[i], splatted += img[i];
    }
    const double entries = double(raster.tile_entries());
    // What evaluating every (tile entry, pixel of the tile) pair would cost at ~20 flops each, per
    // second of compositing: a dense-equivalent rate. Compositing skips the Gaussians that miss a
    // subgroup's pixels and stops where pixels are opaque, so this can exceed the device's FMA rate;
    // its share of that rate says how much the skipping buys, not how busy the FMA units are.
    const double composite_flops = entries * splat::kTile * splat::kTile * 20;
    const double fwd_composite_ms = fwd_passes.count("splat/rasterize_fwd") ? fwd_passes.at("splat/rasterize_fwd") : 0;
    // The two sorts are bandwidth-bound: per 4-bit digit pass each key-value pair is read by the
    // histogram (4 bytes) and read and written by the scatter (16 bytes).
    const auto passes_of = [](std::uint32_t bits) { return double((bits + 3) / 4); };
    const std::uint32_t tiles = splat::tiles_x(rc) * splat::tiles_y(rc);
    const double sort_bytes = entries * 20 * passes_of(gpu::key_bits_for(tiles - 1)) +
                              double(shape.segments()) * 20 * passes_of(splat::depth_bits(rc));
    const double sort_ms = (fwd_passes.count("splat/sort") ? fwd_passes.at("splat/sort") : 0) +
                           (fwd_passes.count("splat/sort_depth") ? fwd_passes.at("splat/sort_depth") : 0);
    const double sort_gbps = sort_ms > 0 ? sort_bytes / (sort_ms * 1e-3) / 1e9 : 0.0;
    json passes_f = json::object(), passes_b = json::object();
    for (const auto& [k, v] : fwd_passes) passes_f[k] = v;
    for (const auto& [k, v] : both_passes) passes_b[k] = v;
    json metrics{{"gaussians", shape.segments()},
                 {"tile_entries", entries},
                 {"walk_passes", double(raster.walk_passes())},
                 {"forward_s", fwd.median()},
                 {"forward_backward_s", both.median()},
                 {"gaussians_per_s_forward", double(shape.segments()) / fwd.median()},
                 {"gaussians_per_s_forward_backward", double(shape.segments()) / both.median()},
                 {"forward_pass_ms", passes_f},
                 {"forward_backward_pass_ms", passes_b},
                 {"composite_dense_equivalent_GFLOPs", fwd_composite_ms > 0 ? composite_flops / (fwd_composite_ms * 1e-3) / 1e9 : 0.0},
                 {"composite_dense_equivalent_fraction_of_fma", fwd_composite_ms > 0 ? composite_flops / (fwd_composite_ms * 1e-3) / 1e9 / fma : 0.0},
                 {"device_fma_GFLOPs", fma},
                 {"sort_traffic_GBps", sort_gbps},
                 {"sort_fraction_of_copy_traffic", sort_gbps / traffic_roof},
                 {"device_copy_traffic_GBps", traffic_roof},
                 {"silhouette_mae_vs_raytraced", abs_err / double(pixels)},
                 {"silhouette_area_ratio_vs_raytraced", covered > 0 ? splatted / covered : 0.0}};
    json params{{"strands", strands}, {"points_per_strand", points}, {"width", w}, {"height", h},
                {"strand_width", rp.gaussian.width}, {"length_scale", rp.gaussian.length_scale}};
    records.push_back(make_record(ctx, kSuite, "rasterize_" + std::to_string(w) + "x" + std::to_string(h), params, both, metrics));
    progress.update(++done, std::to_string(w) + "x" + std::to_string(h));
  }
  progress.finish("done");
  return records;
}

}  // namespace nf::bench
