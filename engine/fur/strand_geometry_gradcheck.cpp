#include "engine/fur/strand_geometry_gradcheck.hpp"

#include <cmath>
#include <random>

#include "engine/fur/strand_geometry.hpp"

namespace nf::fur {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

StrandGeometryShape strand_geometry_shape(const Params& p) {
  return {std::uint32_t(p.at("strands")), std::uint32_t(p.at("segments")), std::uint32_t(p.at("row_stride"))};
}

// Decoder rows like the prior's: segments of about 1/S heading up and along, with noise; padding
// random (it must not matter).
std::vector<double> strand_geometry_rows(std::uint32_t strands, std::uint32_t segments, std::uint32_t stride, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> rows(std::size_t(strands) * stride);
  for (std::uint32_t s = 0; s < strands; ++s)
    for (std::uint32_t c = 0; c < stride; ++c) {
      const double base = c >= 3 * segments ? 0.0 : (c % 3 == 0 ? 0.6 : c % 3 == 2 ? 0.4 : 0.0) / segments;
      rows[std::size_t(s) * stride + c] = base + 0.5 * u(rng) / segments;
    }
  return rows;
}

// Frames: a root around `origin` (spread `spread`), a fur length, and a random orthonormal frame.
std::vector<double> strand_geometry_frames(std::uint32_t strands, double origin, double spread, double length, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> f;
  for (std::uint32_t s = 0; s < strands; ++s) {
    double n[3] = {u(rng), u(rng), u(rng)}, t[3] = {u(rng), u(rng), u(rng)};
    const auto normalise = [](double* v) {
      const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      for (int c = 0; c < 3; ++c) v[c] /= l;
    };
    normalise(n);
    const double dn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
    for (int c = 0; c < 3; ++c) t[c] -= dn * n[c];
    normalise(t);
    const double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
    for (int c = 0; c < 3; ++c) f.push_back(origin + spread * u(rng));
    f.push_back(length * (1.0 + 0.3 * u(rng)));
    f.insert(f.end(), t, t + 3);
    f.insert(f.end(), b, b + 3);
    f.insert(f.end(), n, n + 3);
  }
  return f;
}

namespace {

Case make_case(std::string name, std::uint32_t strands, std::uint32_t segments, std::uint32_t stride, std::vector<double> rows,
               std::vector<double> f) {
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", strands}, {"segments", segments}, {"row_stride", stride}};
  c.inputs = {std::move(rows), std::move(f)};
  c.step_double = {1e-7 / segments * 100, 1e-6};  // the rows' entries are about 1/S
  c.step_float = {1e-2 / segments, 1e-3};         // the frame's entries enter linearly
  return c;
}

class StrandGeometryCheck : public gradcheck::WithReference<StrandGeometryCheck> {
 public:
  std::string name() const override { return "fur/strand_geometry"; }
  std::vector<std::string> input_names() const override { return {"rows", "frames"}; }
  std::vector<std::string> output_names() const override { return {"points"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    // The fur stage's shape: 99 segments in rows of 300 floats (the decoder's padded width).
    cases.push_back(make_case("prior_rows", 2, 99, 300, strand_geometry_rows(2, 99, 300, 1), strand_geometry_frames(2, 0.3, 0.2, 0.05, 2)));
    cases.push_back(make_case("short_strands", 3, 7, 24, strand_geometry_rows(3, 7, 24, 3), strand_geometry_frames(3, -0.5, 0.1, 0.02, 4)));
    {  // The decoder at zero (initialisation): every point at the root, the arc length's guard only.
      Case c = make_case("zero_decoder", 2, 9, 27, std::vector<double>(54, 0.0), strand_geometry_frames(2, 0.1, 0.1, 0.05, 5));
      c.step_double = {1e-10, 1e-6};  // inside the guard delta = 1e-6: the differences stay smooth
      c.step_float = {0.0, 1e-3};
      c.skip_reason = "zero decoder: the points move l / (S delta) per unit of a segment; float differences cannot resolve it";
      cases.push_back(c);
    }
    // Fur of 1e-4 and 1e3 scene units, roots at the same scale.
    cases.push_back(make_case("length_1e-4", 2, 9, 27, strand_geometry_rows(2, 9, 27, 6), strand_geometry_frames(2, 1e-4, 1e-4, 1e-4, 7)));
    cases.push_back(make_case("length_1e3", 2, 9, 27, strand_geometry_rows(2, 9, 27, 8), strand_geometry_frames(2, 1e3, 1e3, 1e3, 9)));
    {  // Roots far from the origin: float cannot resolve the rows' steps on points near 1000.
      Case c = make_case("far_roots", 2, 9, 27, strand_geometry_rows(2, 9, 27, 10), strand_geometry_frames(2, 1000.0, 1.0, 0.05, 11));
      c.step_double = {2e-5, 1e-6};  // double rounding at 1000 needs a wider step; the map is nearly linear in it
      c.step_float = {0.0, 1e-2};
      c.skip_reason = "roots at 1000: a row step moves points by 1e-5 against a float resolution of 6e-5";
      cases.push_back(c);
    }
    return cases;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    Arrays<T> out(1);
    strand_geometry_forward_ref(in[0], in[1], strand_geometry_shape(p), out[0]);
    return out;
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    Arrays<T> grad(2);
    strand_geometry_backward_ref(in[0], in[1], strand_geometry_shape(p), grad_out[0], grad[0], grad[1]);
    return grad;
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    return {strand_points(context, strand_geometry_shape(p), in[0], in[1])};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    StrandGeometryGradients g = strand_points_backward(context, strand_geometry_shape(p), in[0], in[1], grad_out[0]);
    return {std::move(g.rows), std::move(g.frames)};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_geometry_check() { return std::make_unique<StrandGeometryCheck>(); }

}  // namespace nf::fur
