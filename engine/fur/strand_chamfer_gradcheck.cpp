#include "engine/fur/strand_chamfer_gradcheck.hpp"

#include <random>

#include "engine/fur/strand_chamfer.hpp"

namespace nf::fur {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

std::vector<double> cloud(std::size_t n, double spread, double offset, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(3 * n);
  for (double& x : v) x = offset + spread * u(rng);
  return v;
}

// The queries (fixed) and the grid: the box [-scale, scale]^3 in `cells` cells.
std::vector<double> queries_of(const Params& p) {
  return cloud(std::size_t(p.at("queries")), p.at("scale"), 0.0, unsigned(p.at("seed")));
}
ChamferGrid grid_of(const Params& p) {
  const float s = float(p.at("scale"));
  return chamfer_grid(glm::vec3(-s), glm::vec3(s), int(p.at("cells")));
}

template <class T>
std::vector<T> as(const std::vector<double>& v) { return std::vector<T>(v.begin(), v.end()); }

Case make_case(std::string name, std::size_t queries, std::size_t points, double scale, int cells, double spread, double offset) {
  Case c;
  c.name = std::move(name);
  c.params = {{"queries", double(queries)}, {"scale", scale}, {"cells", cells}, {"seed", 3}};
  c.inputs = {cloud(points, spread * scale, offset * scale, 4)};
  c.step_double = {1e-7 * scale};
  c.step_float = {1e-3 * scale};
  return c;
}

class StrandChamferCheck : public gradcheck::WithReference<StrandChamferCheck> {
 public:
  std::string name() const override { return "fur/strand_chamfer"; }
  std::vector<std::string> input_names() const override { return {"points"}; }
  std::vector<std::string> output_names() const override { return {"chamfer"}; }

  std::vector<Case> cases() const override {
    return {make_case("cells_8", 40, 60, 1.0, 8, 1.0, 0.0),
            make_case("one_cell", 30, 50, 1.0, 1, 1.0, 0.0),
            make_case("sparse_fine_grid", 30, 12, 1.0, 64, 1.0, 0.0),         // queries beyond the reach: unmatched
            make_case("points_outside_the_grid", 30, 40, 1.0, 8, 0.8, 1.5),  // searched from the border cells
            make_case("scale_1e-4", 30, 40, 1e-4, 8, 1.0, 0.0),
            make_case("scale_1e3", 30, 40, 1e3, 8, 1.0, 0.0)};
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    return {{strand_chamfer_ref<T>(as<T>(queries_of(p)), in[0], grid_of(p).reach())}};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    return {strand_chamfer_backward_ref<T>(as<T>(queries_of(p)), in[0], grid_of(p).reach(), grad_out[0][0])};
  }

  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    return {{float(strand_chamfer(context, grid_of(p), as<float>(queries_of(p)), in[0]).loss)}};
  }

  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    return {strand_chamfer_gradient(context, grid_of(p), as<float>(queries_of(p)), in[0], grad_out[0][0])};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_chamfer_check() { return std::make_unique<StrandChamferCheck>(); }

}  // namespace nf::fur
