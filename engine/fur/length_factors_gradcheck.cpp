#include "engine/fur/length_factors_gradcheck.hpp"

#include <cmath>

#include "engine/fur/length_factors.hpp"
#include "engine/fur/strand_geometry.hpp"
#include "engine/fur/strand_geometry_gradcheck.hpp"

namespace nf::fur {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

// Inputs: the decoder's rows, the frames with the knowledge's lengths, and one raw factor u per
// region; strand s belongs to region s % regions. Output: the strands' points at lengths
// l0 x lambda(u).
LengthFactorBounds bounds_of(const Params& p) { return {p.at("lo"), p.at("hi")}; }
std::vector<std::int32_t> regions_of(const Params& p) {
  std::vector<std::int32_t> r(std::size_t(p.at("strands")));
  for (std::size_t s = 0; s < r.size(); ++s) r[s] = std::int32_t(s % std::size_t(p.at("regions")));
  return r;
}

template <class T>
std::vector<T> scaled_frames(const Params& p, const Arrays<T>& in) {
  std::vector<T> f = in[1];
  const std::vector<std::int32_t> region = regions_of(p);
  for (std::size_t s = 0; s < region.size(); ++s) f[s * kFrameFloats + 3] *= length_factor_of(in[2][std::size_t(region[s])], bounds_of(p));
  return f;
}

// The frames' gradient at the scaled lengths -> the gradients of the base frames and of u.
template <class T>
void chain(const Params& p, const Arrays<T>& in, std::vector<T>& grad_frames, std::vector<T>& grad_raw) {
  const std::vector<std::int32_t> region = regions_of(p);
  std::vector<T> base(region.size());
  for (std::size_t s = 0; s < region.size(); ++s) base[s] = in[1][s * kFrameFloats + 3];
  const std::vector<double> g =
      length_factor_gradients<T>(region, base, grad_frames, std::size_t(p.at("regions")));
  grad_raw.resize(in[2].size());
  for (std::size_t r = 0; r < grad_raw.size(); ++r) grad_raw[r] = T(g[r]) * length_factor_derivative(in[2][r], bounds_of(p));
  for (std::size_t s = 0; s < region.size(); ++s) grad_frames[s * kFrameFloats + 3] *= length_factor_of(in[2][std::size_t(region[s])], bounds_of(p));
}

Case make_case(std::string name, std::uint32_t strands, std::uint32_t regions, double origin, double length, std::vector<double> raw,
               double lo = 0.4, double hi = 2.5) {
  const std::uint32_t segments = 9, stride = 28;
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", strands}, {"segments", segments}, {"row_stride", stride}, {"regions", regions}, {"lo", lo}, {"hi", hi}};
  c.inputs = {strand_geometry_rows(strands, segments, stride, 1 + strands),
              strand_geometry_frames(strands, origin, 2 * length, length, 2 + strands), std::move(raw)};
  c.step_double = {1e-5 / segments, 1e-6 * length, 1e-5};  // the rows' entries are about 1/S
  c.step_float = {1e-2 / segments, 1e-3 * length, 1e-2};
  return c;
}

class LengthFactorsCheck : public gradcheck::WithReference<LengthFactorsCheck> {
 public:
  std::string name() const override { return "fur/length_factors"; }
  std::vector<std::string> input_names() const override { return {"rows", "frames", "raw_factors"}; }
  std::vector<std::string> output_names() const override { return {"points"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    cases.push_back(make_case("at_one", 6, 3, 0.3, 0.05, {0.0, 0.0, 0.0}));
    cases.push_back(make_case("apart", 7, 3, -0.2, 0.05, {-1.5, 0.7, 2.0}));
    // Near a bound the sigmoid's slope is small but the gradient stays finite and right.
    {
      Case c = make_case("near_bounds", 4, 2, 0.0, 0.05, {-8.0, 8.0});
      // dlambda/du is about 3e-4 here: wider steps (the sigmoid is smooth) for the points to move.
      c.step_double[2] = 1e-3, c.step_float[2] = 0.2;
      cases.push_back(c);
    }
    cases.push_back(make_case("fur_1e-4", 4, 2, 1e-4, 1e-4, {0.5, -0.5}));
    cases.push_back(make_case("fur_1e3", 4, 2, 1e3, 1e3, {0.5, -0.5}));
    // Fixed lengths (lo = hi = 1): lambda is 1 and u has no effect.
    cases.push_back(make_case("fixed", 4, 2, 0.1, 0.05, {0.3, -0.3}, 1.0, 1.0));
    return cases;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    Arrays<T> out(1);
    strand_geometry_forward_ref(in[0], scaled_frames(p, in), strand_geometry_shape(p), out[0]);
    return out;
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    Arrays<T> grad(3);
    strand_geometry_backward_ref(in[0], scaled_frames(p, in), strand_geometry_shape(p), grad_out[0], grad[0], grad[1]);
    chain(p, in, grad[1], grad[2]);
    return grad;
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    return {strand_points(context, strand_geometry_shape(p), in[0], scaled_frames(p, in))};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    StrandGeometryGradients g = strand_points_backward(context, strand_geometry_shape(p), in[0], scaled_frames(p, in), grad_out[0]);
    Arrays<float> grad{std::move(g.rows), std::move(g.frames), {}};
    chain(p, in, grad[1], grad[2]);
    return grad;
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_length_factors_check() { return std::make_unique<LengthFactorsCheck>(); }

}  // namespace nf::fur
