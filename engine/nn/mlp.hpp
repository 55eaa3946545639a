#pragma once
// A multilayer perceptron on the GPU: training forward that keeps what the adjoint needs, the
// adjoint to inputs and parameters (parameter gradients reduced without atomics), and streamed
// inference over batches of any size. Tensors are feature-major (see mlp_config.hpp) except the
// inference entry point, which takes and returns sample-major rows. Shaders: shaders/nn/mlp_*.comp.
#include <memory>
#include <string>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

class Mlp {
 public:
  Mlp(gpu::Context& context, const MlpConfig& config, const std::string& name = "mlp");

  const MlpConfig& config() const { return config_; }
  const std::vector<LayerShape>& layers() const { return layers_; }
  gpu::Buffer<float>& parameters() { return *parameters_; }
  const gpu::Buffer<float>& parameters() const { return *parameters_; }
  gpu::Buffer<float>& gradients() { return *gradients_; }

  // What a training step keeps between forward and backward, sized for one batch.
  class Workspace {
   public:
    Workspace(const Mlp& mlp, std::uint32_t batch);
    std::uint32_t batch() const { return batch_; }
    // The network output of the last forward: output_dim x batch, feature-major.
    gpu::BufferRange output() const { return y_.back()->whole(); }

   private:
    friend class Mlp;
    std::uint32_t batch_;
    std::vector<std::unique_ptr<gpu::Buffer<float>>> y_, z_;  // per layer; z_ only for Sine layers
    std::unique_ptr<gpu::Buffer<float>> grad_a_, grad_b_, partials_;
  };

  // Records the training forward of `input` (input_dim x batch) into the workspace.
  void forward(gpu::Stream& stream, Workspace& workspace, gpu::BufferRange input) const;

  // Records the adjoint. grad_output: output_dim x batch. Parameter gradients are written to
  // gradients() (added when `accumulate`). grad_input, when not empty, receives dL/dinput
  // (input_dim x batch, or batch x input_dim when `grad_input_sample_major`).
  void backward(gpu::Stream& stream, Workspace& workspace, gpu::BufferRange input, gpu::BufferRange grad_output,
                gpu::BufferRange grad_input, bool accumulate, bool grad_input_sample_major = false);

  // Records inference of sample-major `input` (batch x input_dim) into `output` (batch x output_dim),
  // in chunks that fit the device's bindings and a bounded scratch.
  void infer(gpu::Stream& stream, gpu::BufferRange input, gpu::BufferRange output, std::uint64_t batch) const;

  // Floating-point work of one forward / one backward (input and parameter adjoints) per sample.
  double forward_flops_per_sample() const;
  double backward_flops_per_sample() const;

 private:
  void record_layer_forward(gpu::Stream& stream, const LayerShape& layer, gpu::BufferRange x, gpu::BufferRange y,
                            gpu::BufferRange z, std::uint32_t batch, bool input_sample_major,
                            bool output_sample_major) const;

  gpu::Context& context_;
  MlpConfig config_;
  std::vector<LayerShape> layers_;
  std::unique_ptr<gpu::Buffer<float>> parameters_, gradients_;
};

}  // namespace nf::nn
