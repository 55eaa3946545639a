#include "engine/fur/strand_losses_gradcheck.hpp"

#include <cmath>
#include <random>

#include "engine/fur/strand_losses.hpp"

namespace nf::fur {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

// The fixed (non-differentiated) inputs of a case, made from its parameters: growth directions,
// fur lengths, and a sphere's SDF of radius 0.5 * scale on a 9^3 grid over [-scale, scale]^3.
struct Fixed {
  StrandLossShape shape;
  SdfGridRef grid;
  std::vector<double> guides, lengths, sdf;
};

Fixed fixed_of(const Params& p) {
  Fixed f;
  f.shape = {std::uint32_t(p.at("strands")), std::uint32_t(p.at("points_per_strand"))};
  const double scale = p.at("scale");
  f.grid.dims = {9, 9, 9};
  f.grid.origin = {-scale, -scale, -scale};
  f.grid.spacing = 2 * scale / 8;
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) {
        const double x = -scale + f.grid.spacing * i, y = -scale + f.grid.spacing * j, z = -scale + f.grid.spacing * k;
        f.sdf.push_back(std::sqrt(x * x + y * y + z * z) - 0.5 * scale);
      }
  std::mt19937 rng(unsigned(p.at("seed")));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::uint32_t s = 0; s < f.shape.strands; ++s) {
    double g[3] = {u(rng), u(rng), u(rng)};
    const double n = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (double& x : g) f.guides.push_back(x / n);
    f.lengths.push_back(p.at("length"));
  }
  return f;
}

template <class T>
std::vector<T> as(const std::vector<double>& v) { return std::vector<T>(v.begin(), v.end()); }

// Strands from roots on a shell of radius ~0.5 scale, random walks of `segment` per step (bend
// `wiggle`); some points sink into the sphere.
std::vector<double> strands(std::uint32_t n, std::uint32_t L, double scale, double segment, double wiggle, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> pts;
  for (std::uint32_t s = 0; s < n; ++s) {
    double dir[3] = {u(rng), u(rng), u(rng)};
    double p[3] = {0.5 * scale * dir[0], 0.5 * scale * dir[1], 0.5 * scale * dir[2]};
    for (std::uint32_t l = 0; l < L; ++l) {
      pts.insert(pts.end(), p, p + 3);
      for (double& d : dir) d += wiggle * u(rng);
      const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
      for (int c = 0; c < 3; ++c) p[c] += segment * dir[c] / len;
    }
  }
  return pts;
}

Case make_case(std::string name, std::uint32_t n, std::uint32_t L, double scale, std::vector<double> points, double segment) {
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", n}, {"points_per_strand", L}, {"scale", scale}, {"length", segment * (L - 1)}, {"seed", 5}};
  c.inputs = {std::move(points)};
  c.step_double = {1e-7 * segment};
  c.step_float = {1e-3 * segment};
  return c;
}

class StrandLossesCheck : public gradcheck::WithReference<StrandLossesCheck> {
 public:
  std::string name() const override { return "fur/strand_losses"; }
  std::vector<std::string> input_names() const override { return {"points"}; }
  std::vector<std::string> output_names() const override { return {"losses"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    cases.push_back(make_case("wavy", 4, 12, 1.0, strands(4, 12, 1.0, 0.05, 0.4, 1), 0.05));
    {  // Straight strands: every bending angle at the guard, where arccos would have an infinite slope.
      Case c = make_case("straight", 3, 8, 1.0, strands(3, 8, 1.0, 0.05, 0.0, 2), 0.05);
      c.step_double = {1e-9};  // the guarded angle is even in the bend: central differences stay exact
      c.step_float = {0.0};
      c.skip_reason = "straight strands: the guarded angle curves over 1e-6 in direction, below float's step";
      cases.push_back(c);
    }
    {  // Zero-length segments: repeated points, held finite by the segment guard.
      std::vector<double> pts = strands(2, 8, 1.0, 0.05, 0.3, 3);
      for (int c = 0; c < 3; ++c) pts[9 + c] = pts[6 + c];
      Case c = make_case("zero_length_segment", 2, 8, 1.0, pts, 0.05);
      // The zero segment's direction is ~0, so its bend angles curve over eps * delta = 5e-11 in
      // point space (gradients near 1e9, finite): the step must be far inside that.
      c.step_double = {1e-14};
      c.step_float = {0.0};
      c.skip_reason = "a zero-length segment's direction turns over the guard (5e-5): float differences cannot resolve it";
      cases.push_back(c);
    }
    cases.push_back(make_case("scale_1e-4", 3, 10, 1e-4, strands(3, 10, 1e-4, 5e-6, 0.4, 4), 5e-6));
    cases.push_back(make_case("scale_1e3", 3, 10, 1e3, strands(3, 10, 1e3, 50.0, 0.4, 5), 50.0));
    // Strands leaving the SDF grid's box: clamped values, zero gradient outside.
    cases.push_back(make_case("leaving_the_grid", 3, 10, 1.0, strands(3, 10, 1.0, 0.15, 0.2, 6), 0.15));
    return cases;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const Fixed f = fixed_of(p);
    const std::array<T, 3> l = strand_losses_ref<T>(in[0], as<T>(f.guides), as<T>(f.lengths), f.grid, as<T>(f.sdf), f.shape);
    return {{l[0], l[1], l[2]}};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    const Fixed f = fixed_of(p);
    Arrays<T> grad(1);
    strand_losses_backward_ref<T>(in[0], as<T>(f.guides), as<T>(f.lengths), f.grid, as<T>(f.sdf), f.shape,
                                  {grad_out[0][0], grad_out[0][1], grad_out[0][2]}, grad[0]);
    return grad;
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    const Fixed f = fixed_of(p);
    const std::array<double, 3> l = strand_losses(context, f.shape, f.grid, in[0], as<float>(f.guides), as<float>(f.lengths), as<float>(f.sdf));
    return {{float(l[0]), float(l[1]), float(l[2])}};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    const Fixed f = fixed_of(p);
    const StrandLossWeights w{grad_out[0][0], grad_out[0][1], grad_out[0][2]};
    return {strand_losses_gradient(context, f.shape, f.grid, in[0], as<float>(f.guides), as<float>(f.lengths), as<float>(f.sdf), w)};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_losses_check() { return std::make_unique<StrandLossesCheck>(); }

}  // namespace nf::fur
