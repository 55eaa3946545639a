#include "engine/nn/encoding_gradcheck.hpp"

#include <random>

#include "engine/gpu/context.hpp"
#include "engine/nn/frequency_encoding.hpp"
#include "engine/nn/hash_grid.hpp"

namespace nf::nn {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

std::vector<double> uniform_points(std::size_t n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

FrequencyEncodingConfig frequency_config(const Params& p) {
  return {std::uint32_t(p.at("dims")), std::uint32_t(p.at("frequencies")), p.at("include_input") != 0};
}

class FrequencyEncodingCheck : public gradcheck::WithReference<FrequencyEncodingCheck> {
 public:
  std::string name() const override { return "nn/frequency_encoding"; }
  std::vector<std::string> input_names() const override { return {"points"}; }
  std::vector<std::string> output_names() const override { return {"encoded"}; }

  std::vector<Case> cases() const override {
    Case unit;
    unit.name = "unit_box";
    unit.params = {{"dims", 3}, {"frequencies", 10}, {"include_input", 1}, {"batch", 37}};
    unit.inputs = {uniform_points(37 * 3, -1, 1, 1)};
    // sin(2^9 x) bends on a scale of 1/512: steps well below it.
    unit.step_double = {1e-7};
    unit.step_float = {1e-4};
    Case far;
    far.name = "far_1e3";
    far.params = {{"dims", 3}, {"frequencies", 10}, {"include_input", 0}, {"batch", 21}};
    far.inputs = {uniform_points(21 * 3, -1e3, 1e3, 2)};
    far.step_double = {1e-7};
    far.step_float = {0};
    far.skip_reason = "at |x| = 1e3 a float step (ulp 6e-5) is not small against the period 0.012";
    Case odd;
    odd.name = "dims2_L4";
    odd.params = {{"dims", 2}, {"frequencies", 4}, {"include_input", 1}, {"batch", 5}};
    odd.inputs = {uniform_points(5 * 2, -1, 1, 3)};
    odd.step_double = {1e-7};
    odd.step_float = {1e-3};
    return {unit, far, odd};
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    return {frequency_encoding_forward_ref(frequency_config(p), in[0], std::uint32_t(p.at("batch")))};
  }
  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& g) const {
    return {frequency_encoding_backward_ref(frequency_config(p), in[0], std::uint32_t(p.at("batch")), g[0])};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    const FrequencyEncoding enc(frequency_config(p));
    const std::uint32_t batch = std::uint32_t(p.at("batch"));
    gpu::Buffer<float> points(ctx, std::span<const float>(in[0]), "points");
    gpu::Buffer<float> encoded(ctx, std::uint64_t(enc.config().output_stride()) * batch, "encoded");
    gpu::Stream s(ctx);
    enc.forward(s, points, encoded, batch);
    s.submit_and_wait();
    return {encoded.download()};
  }

  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    const FrequencyEncoding enc(frequency_config(p));
    const std::uint32_t batch = std::uint32_t(p.at("batch"));
    gpu::Buffer<float> points(ctx, std::span<const float>(in[0]), "points");
    gpu::Buffer<float> grad(ctx, std::span<const float>(g[0]), "grad encoded");
    gpu::Buffer<float> grad_points(ctx, in[0].size(), "grad points");
    gpu::Stream s(ctx);
    enc.backward(s, points, grad, grad_points, batch, false);
    s.submit_and_wait();
    return {grad_points.download()};
  }
};

HashGridConfig grid_config(const Params& p) {
  HashGridConfig c;
  c.levels = std::uint32_t(p.at("levels"));
  c.features = std::uint32_t(p.at("features"));
  c.log2_table = std::uint32_t(p.at("log2_table"));
  c.base_resolution = std::uint32_t(p.at("base"));
  c.max_resolution = std::uint32_t(p.at("max"));
  return c;
}

class HashGridCheck : public gradcheck::WithReference<HashGridCheck> {
 public:
  std::string name() const override { return "nn/hash_grid"; }
  std::vector<std::string> input_names() const override { return {"points", "table"}; }
  std::vector<std::string> output_names() const override { return {"encoded"}; }

  std::vector<Case> cases() const override {
    // Levels at 2, 5, 12, 32 cells with a 256-entry table: two dense levels, two hashed ones.
    const Params p{{"levels", 4}, {"features", 2}, {"log2_table", 8}, {"base", 2}, {"max", 32}, {"batch", 29}};
    const HashGridConfig c = grid_config(p);
    Case random;
    random.name = "random";
    random.params = p;
    random.inputs = {uniform_points(29 * 3, 0.02, 0.98, 4), uniform_points(c.parameter_count(), -1, 1, 5)};
    random.step_double = {1e-9, 1e-6};  // cells are 1/32 wide: stay inside them
    random.step_float = {1e-5, 1e-2};   // the table enters linearly: any step is exact
    Case faces;
    faces.name = "faces_corners";
    faces.params = p;
    faces.params["batch"] = 6;
    // Exactly on cell faces, edges and corners of every level, and on the box's own faces.
    faces.inputs = {{0.5, 0.25, 0.125, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 0.03125, 0.75, 0.3, 1.0, 0.0, 0.6},
                    uniform_points(c.parameter_count(), -1, 1, 6)};
    faces.step_double = {0, 1e-6};
    faces.step_float = {0, 1e-2};
    faces.skip_reason = "the encoding has a kink at cell faces: one-sided adjoint, two-sided differences";
    return {random, faces};
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    return {hash_grid_forward_ref(grid_config(p), in[0], in[1], std::uint32_t(p.at("batch")))};
  }
  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& g) const {
    std::vector<T> grad_table;
    std::vector<T> grad_points =
        hash_grid_backward_ref(grid_config(p), in[0], in[1], std::uint32_t(p.at("batch")), g[0], grad_table);
    return {grad_points, grad_table};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    const HashGrid grid(grid_config(p));
    const std::uint32_t batch = std::uint32_t(p.at("batch"));
    gpu::Buffer<float> points(ctx, std::span<const float>(in[0]), "points");
    gpu::Buffer<float> table(ctx, std::span<const float>(in[1]), "table");
    gpu::Buffer<float> encoded(ctx, std::uint64_t(grid.config().output_stride()) * batch, "encoded");
    gpu::Stream s(ctx);
    grid.forward(s, points, table, encoded, batch);
    s.submit_and_wait();
    return {encoded.download()};
  }

  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    const HashGrid grid(grid_config(p));
    const std::uint32_t batch = std::uint32_t(p.at("batch"));
    gpu::Buffer<float> points(ctx, std::span<const float>(in[0]), "points");
    gpu::Buffer<float> table(ctx, std::span<const float>(in[1]), "table");
    gpu::Buffer<float> grad(ctx, std::span<const float>(g[0]), "grad encoded");
    gpu::Buffer<float> grad_table(ctx, in[1].size(), "grad table");
    gpu::Buffer<float> grad_points(ctx, in[0].size(), "grad points");
    grad_table.fill_u32(0);
    gpu::Stream s(ctx);
    grid.backward(s, points, table, grad, grad_table, grad_points, batch, false);
    s.submit_and_wait();
    return {grad_points.download(), grad_table.download()};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_hash_grid_check() { return std::make_unique<HashGridCheck>(); }

std::unique_ptr<gradcheck::DifferentiableKernel> make_frequency_encoding_check() {
  return std::make_unique<FrequencyEncodingCheck>();
}

}  // namespace nf::nn
