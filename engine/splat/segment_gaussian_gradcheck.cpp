#include "engine/splat/segment_gaussian_gradcheck.hpp"

#include <random>

#include "engine/splat/segment_gaussian.hpp"

namespace nf::splat {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

StrandShape shape_of(const Params& p) {
  return {std::uint32_t(p.at("strands")), std::uint32_t(p.at("points_per_strand"))};
}
SegmentGaussianParams params_of(const Params& p) { return {p.at("length_scale"), p.at("width")}; }

// Random-walk strands: `segment` is the typical segment length, `origin` where the strands start.
std::vector<double> walk(std::uint32_t strands, std::uint32_t L, double segment, double origin, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> pts;
  for (std::uint32_t s = 0; s < strands; ++s) {
    double p[3] = {origin + segment * u(rng), origin + segment * u(rng), origin + segment * u(rng)};
    for (std::uint32_t l = 0; l < L; ++l) {
      pts.insert(pts.end(), p, p + 3);
      for (double& x : p) x += segment * (0.3 + 0.7 * std::fabs(u(rng))) * (u(rng) < 0 ? -1 : 1);
    }
  }
  return pts;
}

Case make_case(std::string name, std::uint32_t strands, std::uint32_t L, double width, std::vector<double> points,
               double length_scale_of_variation) {
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", strands}, {"points_per_strand", L}, {"length_scale", 0.5}, {"width", width}};
  c.inputs = {std::move(points)};
  c.step_double = {1e-6 * length_scale_of_variation};
  c.step_float = {1e-2 * length_scale_of_variation};
  return c;
}

class SegmentGaussianCheck : public gradcheck::WithReference<SegmentGaussianCheck> {
 public:
  std::string name() const override { return "splat/segment_gaussian"; }
  std::vector<std::string> input_names() const override { return {"points"}; }
  std::vector<std::string> output_names() const override { return {"means", "covariances"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    // Typical fur: segments much longer than the width.
    cases.push_back(make_case("long_segments", 3, 6, 0.0025, walk(3, 6, 0.05, 0.0, 7), 0.05));
    // Segments comparable to the width, where the eps^2/|d|^2 term matters.
    cases.push_back(make_case("width_sized", 3, 6, 0.02, walk(3, 6, 0.02, 0.0, 8), 0.02));
    // Segments much shorter than the width (short fur at 100 points per strand).
    cases.push_back(make_case("short_segments", 2, 5, 0.01, walk(2, 5, 0.001, 0.0, 9), 0.001));
    {  // Exactly zero-length and near-zero segments: repeated points and a 1e-7 step.
      std::vector<double> pts = walk(2, 5, 0.01, 0.0, 10);
      for (int j = 0; j < 3; ++j) pts[3 + j] = pts[j];                 // strand 0: p1 == p0
      for (int j = 0; j < 3; ++j) pts[9 + j] = pts[6 + j] + 1e-7 * (j + 1);  // p3 = p2 + 1e-7
      for (int j = 0; j < 3; ++j) pts[18 + j] = pts[15 + j];           // strand 1: p1 == p0
      Case c = make_case("zero_length", 2, 5, 0.01, pts, 0.01);
      c.step_double = {1e-9};  // below the guard scale delta = 1e-5 so the differences stay smooth
      c.step_float = {2e-7};  // well inside delta, still hundreds of float ulps at these coordinates
      cases.push_back(c);
    }
    // Tiny and huge scenes: everything (points, width) scaled by 1e-6 and 1e3.
    {
      std::vector<double> pts = walk(2, 5, 0.05, 0.0, 11);
      for (double& x : pts) x *= 1e-6;
      cases.push_back(make_case("tiny_scene_1e-6", 2, 5, 0.0025e-6, pts, 0.05e-6));
    }
    {
      std::vector<double> pts = walk(2, 5, 0.05, 0.0, 12);
      for (double& x : pts) x *= 1e3;
      cases.push_back(make_case("huge_scene_1e3", 2, 5, 2.5, pts, 50.0));
    }
    {  // Far from the origin: float resolves far less there, so check 4 uses a coarser step.
      Case c = make_case("far_from_origin", 2, 5, 0.0025, walk(2, 5, 0.05, 1000.0, 13), 0.05);
      // Quadratic in d and linear in the mean: wide steps stay exact and beat the rounding of ~1e3.
      c.step_double = {5e-6};
      c.step_float = {0.01};
      cases.push_back(c);
    }
    return cases;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const StrandShape shape = shape_of(p);
    Arrays<T> out(2);
    segment_gaussian_forward_ref(in[0], shape.strands, shape.points_per_strand, params_of(p), out[0], out[1]);
    return out;
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    const StrandShape shape = shape_of(p);
    Arrays<T> grad(1);
    segment_gaussian_backward_ref(in[0], shape.strands, shape.points_per_strand, params_of(p), grad_out[0],
                                  grad_out[1], grad[0]);
    return grad;
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    SegmentGaussians g = segment_gaussians(context, shape_of(p), params_of(p), in[0]);
    return {std::move(g.means), std::move(g.covariances)};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    return {segment_gaussians_backward(context, shape_of(p), params_of(p), in[0], grad_out[0], grad_out[1])};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_segment_gaussian_check() {
  return std::make_unique<SegmentGaussianCheck>();
}

}  // namespace nf::splat
