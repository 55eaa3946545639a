#include "engine/nn/loss_gradcheck.hpp"

#include <random>

#include "engine/gpu/context.hpp"
#include "engine/nn/loss.hpp"

namespace nf::nn {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

class MseLossCheck : public gradcheck::WithReference<MseLossCheck> {
 public:
  std::string name() const override { return "nn/loss_mse"; }
  std::vector<std::string> input_names() const override { return {"prediction"}; }
  std::vector<std::string> output_names() const override { return {"loss"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    for (auto [batch, dims] : {std::pair{37u, 3u}, std::pair{300u, 1u}}) {
      const std::uint32_t stride = (dims + 3u) & ~3u;
      std::mt19937 rng(batch);
      std::uniform_real_distribution<double> u(-1, 1);
      std::vector<double> prediction(std::size_t(batch) * stride, 0.0);
      for (std::uint32_t s = 0; s < batch; ++s)
        for (std::uint32_t d = 0; d < dims; ++d) prediction[s * stride + d] = u(rng);
      Case c;
      c.name = "batch" + std::to_string(batch) + "_dims" + std::to_string(dims);
      c.params = {{"batch", batch}, {"dims", dims}, {"stride", stride}, {"seed", batch}};
      c.inputs = {prediction};
      c.step_double = {1e-6};
      c.step_float = {1e-2};  // quadratic: central differences are exact
      cases.push_back(c);
    }
    return cases;
  }

  // The target is fixed per case (a function of its seed), not an input.
  static std::vector<double> target(const Params& p) {
    std::mt19937 rng(unsigned(p.at("seed")) + 1000);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> t(std::size_t(p.at("batch")) * std::size_t(p.at("dims")));
    for (double& x : t) x = u(rng);
    return t;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const auto b = std::uint32_t(p.at("batch")), dims = std::uint32_t(p.at("dims")), stride = std::uint32_t(p.at("stride"));
    const auto t = target(p);
    T loss = 0;
    for (std::uint32_t s = 0; s < b; ++s)
      for (std::uint32_t d = 0; d < dims; ++d) {
        const T r = in[0][s * stride + d] - T(t[s * dims + d]);
        loss += r * r;
      }
    return {{loss / T(b * dims)}};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& g) const {
    const auto b = std::uint32_t(p.at("batch")), dims = std::uint32_t(p.at("dims")), stride = std::uint32_t(p.at("stride"));
    const auto t = target(p);
    std::vector<T> grad(in[0].size(), T(0));
    for (std::uint32_t s = 0; s < b; ++s)
      for (std::uint32_t d = 0; d < dims; ++d)
        grad[s * stride + d] = g[0][0] * T(2) * (in[0][s * stride + d] - T(t[s * dims + d])) / T(b * dims);
    return {grad};
  }

  Arrays<float> run(gpu::Context& ctx, const Params& p, const std::vector<float>& prediction, float upstream,
                    bool want_grad) const {
    const auto b = std::uint32_t(p.at("batch")), dims = std::uint32_t(p.at("dims")), stride = std::uint32_t(p.at("stride"));
    const auto t = target(p);
    const std::vector<float> tf(t.begin(), t.end());
    gpu::Buffer<float> d_pred(ctx, std::span<const float>(prediction), "prediction");
    gpu::Buffer<float> d_target(ctx, std::span<const float>(tf), "target");
    gpu::Buffer<float> d_grad(ctx, prediction.size(), "grad"), d_loss(ctx, 1, "loss");
    gpu::Stream s(ctx);
    mse_loss(s, d_pred, d_target, d_grad, d_loss, b, dims, stride);
    s.submit_and_wait();
    if (!want_grad) return {d_loss.download()};
    auto grad = d_grad.download();
    for (float& x : grad) x *= upstream;
    return {grad};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    return run(ctx, p, in[0], 1.f, false);
  }
  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    return run(ctx, p, in[0], g[0][0], true);
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_mse_loss_check() { return std::make_unique<MseLossCheck>(); }

}  // namespace nf::nn
