#include "engine/splat/rasterizer_gradcheck.hpp"

#include <random>

#include "engine/splat/rasterizer.hpp"

namespace nf::splat {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

StrandShape shape_of(const Params& p) { return {std::uint32_t(p.at("strands")), std::uint32_t(p.at("points_per_strand"))}; }

// A camera at (0, 0, distance) looking down -z at the origin.
RasterCamera camera_of(const Params& p) {
  RasterCamera c;
  c.width = std::uint32_t(p.at("width_px")), c.height = std::uint32_t(p.at("height_px"));
  c.fx = c.fy = p.at("focal");
  c.cx = 0.5 * c.width, c.cy = 0.5 * c.height;
  c.world_to_camera[3] = 0, c.world_to_camera[7] = 0, c.world_to_camera[11] = -p.at("distance");
  c.near = 0.1, c.far = 10;
  return c;
}

RasterParams params_of(const Params& p) {
  RasterParams r;
  r.gaussian = {0.5, p.at("strand_width")};
  r.walk_chunk = std::uint32_t(p.at("walk_chunk"));
  return r;
}

// An occluder covering the pixels left of `occluder_x` at depth `occluder_depth` (none if 0).
std::vector<float> body_of(const Params& p) {
  if (p.at("occluder_depth") <= 0) return {};
  const RasterCamera c = camera_of(p);
  std::vector<float> depth(std::size_t(c.width) * c.height, 1e30f);
  for (std::uint32_t y = 0; y < c.height; ++y)
    for (std::uint32_t x = 0; x < std::uint32_t(p.at("occluder_x")) && x < c.width; ++x)
      depth[std::size_t(y) * c.width + x] = float(p.at("occluder_depth"));
  return depth;
}

// Strands crossing the view near the origin: smooth random walks, confidences in [0.3, 1].
Case make_case(std::string name, std::uint32_t strands, std::uint32_t L, double extent, unsigned seed, Params extra) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> pts, conf;
  for (std::uint32_t s = 0; s < strands; ++s) {
    double p[3] = {extent * u(rng), extent * u(rng), 0.2 * u(rng)};
    double d[3] = {u(rng), u(rng), 0.3 * u(rng)};
    for (std::uint32_t l = 0; l < L; ++l) {
      pts.insert(pts.end(), p, p + 3);
      for (int k = 0; k < 3; ++k) d[k] += 0.4 * u(rng), p[k] += 0.35 * extent * d[k] / 1.5;
    }
    for (std::uint32_t l = 0; l + 1 < L; ++l) conf.push_back(0.3 + 0.35 * (1 + u(rng)));
  }
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", strands}, {"points_per_strand", L}, {"width_px", 24}, {"height_px", 20}, {"focal", 30},
              {"distance", 2}, {"strand_width", 0.05}, {"occluder_depth", 0}, {"occluder_x", 0},
              {"walk_chunk", 0}};
  for (const auto& [k, v] : extra) c.params[k] = v;
  c.inputs = {pts, conf};
  c.step_double = {1e-7, 1e-7};
  // Small enough that the alpha >= 1/255 cut-off is rarely crossed (a crossing jumps by ~1/255),
  // large enough for float to resolve the change of the weighted sum.
  c.step_float = {2e-4, 2e-3};
  return c;
}

class RasterizerCheck : public gradcheck::WithReference<RasterizerCheck> {
 public:
  std::string name() const override { return "splat/rasterize"; }
  std::vector<std::string> input_names() const override { return {"points", "confidence"}; }
  std::vector<std::string> output_names() const override { return {"image"}; }

  std::vector<Case> cases() const override {
    return {make_case("two_strands", 2, 5, 0.3, 3, {}),
            make_case("tiles_and_overlap", 4, 6, 0.6, 5, {{"width_px", 40}, {"height_px", 36}}),
            make_case("occluded_left", 3, 5, 0.4, 7, {{"occluder_depth", 1.0}, {"occluder_x", 10}}),
            // Tile lists walked 3 entries a pass (devices with a loop limit walk long lists in
            // passes): partial batches, and each subgroup's walk ending in a different pass.
            make_case("walked_in_passes", 8, 6, 0.3, 11, {{"width_px", 24}, {"height_px", 20}, {"walk_chunk", 3},
                                                         {"occluder_depth", 1.95}, {"occluder_x", 9}})};
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const StrandShape s = shape_of(p);
    Arrays<T> out(1);
    rasterize_ref(in[0], in[1], s.strands, s.points_per_strand, camera_of(p), params_of(p), body_of(p), out[0]);
    return out;
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    const StrandShape s = shape_of(p);
    Arrays<T> grad(2);
    rasterize_adjoint_ref(in[0], in[1], s.strands, s.points_per_strand, camera_of(p), params_of(p), body_of(p), grad_out[0],
                          grad[0], grad[1]);
    return grad;
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    const std::vector<float> body = body_of(p);
    return {rasterize(context, shape_of(p), in[0], in[1], camera_of(p), params_of(p), body)};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    const std::vector<float> body = body_of(p);
    RasterGradients g = rasterize_backward(context, shape_of(p), in[0], in[1], camera_of(p), params_of(p), body, grad_out[0]);
    return {std::move(g.points), std::move(g.confidence)};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_rasterizer_check() { return std::make_unique<RasterizerCheck>(); }

}  // namespace nf::splat
