#include "engine/nn/mlp_gradcheck.hpp"

#include <map>
#include <random>

#include "engine/gpu/context.hpp"
#include "engine/nn/mlp.hpp"
#include "engine/nn/mlp_ref.hpp"

namespace nf::nn {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

MlpConfig config_of(const Params& p) {
  MlpConfig c;
  c.input_dim = std::uint32_t(p.at("in"));
  c.hidden = {std::uint32_t(p.at("hidden0")), std::uint32_t(p.at("hidden1"))};
  c.output_dim = std::uint32_t(p.at("out"));
  c.hidden_activation = {Activation(std::uint32_t(p.at("activation"))), float(p.at("beta")), float(p.at("omega"))};
  c.output_activation = {Activation(std::uint32_t(p.at("output_activation"))), float(p.at("beta")), float(p.at("omega"))};
  return c;
}

struct Dims {
  std::uint32_t in = 5, hidden0 = 16, hidden1 = 7, out = 3;
};

Case make_case(const std::string& name, Activation act, Activation out_act, std::uint32_t batch, double input_scale,
               double beta, double omega, unsigned seed, Dims d = {}) {
  Params p{{"in", d.in}, {"hidden0", d.hidden0}, {"hidden1", d.hidden1}, {"out", d.out}, {"batch", batch},
           {"activation", double(act)}, {"output_activation", double(out_act)}, {"beta", beta}, {"omega", omega}};
  const MlpConfig c = config_of(p);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> params(c.parameter_count());
  for (const LayerShape& l : c.layers()) {
    const double bound = (act == Activation::Sine ? 1.0 / omega : 1.0) * std::sqrt(6.0 / l.in);
    for (std::uint32_t o = 0; o < l.out; ++o)
      for (std::uint32_t k = 0; k < l.in; ++k) params[l.weight_offset + std::uint64_t(o) * l.in_stride + k] = bound * u(rng);
    for (std::uint32_t o = 0; o < l.out; ++o) params[l.bias_offset + o] = 0.1 * u(rng);
  }
  const std::uint32_t stride = pad4(c.input_dim);
  std::vector<double> input(std::size_t(stride) * batch, 0.0);  // padding columns stay zero
  for (std::uint32_t s = 0; s < batch; ++s)
    for (std::uint32_t k = 0; k < c.input_dim; ++k) input[std::size_t(s) * stride + k] = input_scale * u(rng);
  Case cs;
  cs.name = name;
  cs.params = p;
  cs.inputs = {params, input};
  cs.step_double = {1e-6, 1e-6 * input_scale};
  cs.step_float = {1e-3, 1e-3 * input_scale};
  return cs;
}

// ReLU has kinks: a float difference step that straddles one sees the mean of both slopes. A step
// of 1e-4 keeps straddles rare while float rounding stays ~1e-3 of the gradient.
Case relu_case() {
  Case c = make_case("relu", Activation::ReLU, Activation::None, 37, 1.0, 100, 30, 1);
  c.step_float = {1e-4, 1e-4};
  return c;
}

// beta * x far past the linear switch (exp(500) overflows float) on inputs of +-50. beta = 10
// keeps the bend wide enough (~0.1) for float central differences of outputs in the hundreds.
Case softplus_big_case() {
  Case c = make_case("softplus_big_x", Activation::Softplus, Activation::Softplus, 33, 50.0, 10, 30, 3);
  c.step_float = {2e-3, 1e-2};
  return c;
}

// Layers wider than one mlp_fwd dispatch: 300 inputs split into chunks that accumulate (64 + 11
// vec4 with 32 KiB of shared memory) and outputs into row blocks with a short last one (70 = 32 +
// 32 + 6). Finite differences over ~25k parameters would take minutes; the small cases cover them,
// so this one checks the device against the reference only.
Case wide_case() {
  Case c = make_case("wide_chunked", Activation::Softplus, Activation::None, 37, 1.0, 10, 30, 6, {300, 70, 40, 3});
  c.step_double = {0.0, 0.0};
  c.step_float = {0.0, 0.0};
  return c;
}

// The strand prior's decoder (engine/fur/strand_prior.hpp): 64 latents to 297 segment values.
// At its shipped widths (128, 128) the device is checked against the reference only (finite
// differences over 63k parameters would take many minutes); narrow hidden layers with the same
// input and output widths are checked against finite differences too.
Case strand_decoder_case() {
  Case c = make_case("strand_decoder", Activation::ReLU, Activation::None, 9, 1.0, 100, 30, 8, {64, 128, 128, 297});
  c.step_double = {0.0, 0.0};
  c.step_float = {0.0, 0.0};
  return c;
}
Case strand_decoder_narrow_case() {
  Case c = make_case("strand_decoder_narrow", Activation::ReLU, Activation::None, 5, 1.0, 100, 30, 9, {64, 8, 8, 297});
  c.step_float = {1e-4, 1e-4};
  return c;
}

class MlpCheck : public gradcheck::WithReference<MlpCheck> {
 public:
  std::string name() const override { return "nn/mlp"; }
  std::vector<std::string> input_names() const override { return {"parameters", "input"}; }
  std::vector<std::string> output_names() const override { return {"output"}; }

  std::vector<Case> cases() const override {
    return {
        relu_case(),
        make_case("softplus", Activation::Softplus, Activation::None, 70, 1.0, 100, 30, 2),
        // beta * x far past the linear switch: exp would overflow without the guard.
        softplus_big_case(),
        make_case("sine_siren", Activation::Sine, Activation::None, 65, 1.0, 100, 30, 4),
        make_case("none_linear", Activation::None, Activation::Sine, 129, 1.0, 100, 2, 5),
        wide_case(),
        strand_decoder_case(),
        strand_decoder_narrow_case(),
    };
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    return {mlp_forward_ref(config_of(p), in[0], in[1], std::uint32_t(p.at("batch"))).y.back()};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    const MlpConfig c = config_of(p);
    const std::uint32_t batch = std::uint32_t(p.at("batch"));
    const auto trace = mlp_forward_ref(c, in[0], in[1], batch);
    std::vector<T> grad_params;
    std::vector<T> grad_input = mlp_backward_ref(c, in[0], in[1], batch, trace, grad_out[0], grad_params);
    return {grad_params, grad_input};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    Resources& r = resources(ctx, p);
    r.mlp.parameters().upload(in[0]);
    r.input.upload(in[1]);
    gpu::Stream s(ctx);
    r.mlp.forward(s, r.workspace, r.input);
    s.submit_and_wait();
    std::vector<float> out(r.workspace.output().size / 4);
    r.workspace.output().buffer->read_bytes(0, out.data(), r.workspace.output().size);
    return {out};
  }

  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    Resources& r = resources(ctx, p);
    r.mlp.parameters().upload(in[0]);
    r.input.upload(in[1]);
    r.grad_output.upload(grad_out[0]);
    gpu::Stream s(ctx);
    r.mlp.forward(s, r.workspace, r.input);
    r.mlp.backward(s, r.workspace, r.input, r.grad_output, r.grad_input, false);
    s.submit_and_wait();
    return {r.mlp.gradients().download(), r.grad_input.download()};
  }

 private:
  // Finite differences run the forward thousands of times: keep the network and buffers per case.
  struct Resources {
    Mlp mlp;
    Mlp::Workspace workspace;
    gpu::Buffer<float> input, grad_output, grad_input;
    Resources(gpu::Context& ctx, const MlpConfig& c, std::uint32_t batch)
        : mlp(ctx, c), workspace(mlp, batch), input(ctx, std::uint64_t(mlp.input_stride()) * batch, "mlp input"),
          grad_output(ctx, std::uint64_t(mlp.output_stride()) * batch, "mlp grad output"),
          grad_input(ctx, std::uint64_t(mlp.input_stride()) * batch, "mlp grad input") {}
  };
  Resources& resources(gpu::Context& ctx, const Params& p) const {
    std::string key;
    for (const auto& [k, v] : p) key += k + "=" + std::to_string(v) + ";";
    auto& slot = cache_[key];
    if (!slot || slot->context != &ctx) slot = std::make_unique<Cached>(Cached{&ctx, std::make_unique<Resources>(ctx, config_of(p), std::uint32_t(p.at("batch")))});
    return *slot->resources;
  }
  struct Cached {
    gpu::Context* context;
    std::unique_ptr<Resources> resources;
  };
  mutable std::map<std::string, std::unique_ptr<Cached>> cache_;
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_mlp_check() { return std::make_unique<MlpCheck>(); }

}  // namespace nf::nn
