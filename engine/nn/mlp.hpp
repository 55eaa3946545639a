#pragma once
// A multilayer perceptron on the GPU: training forward that keeps what the adjoint needs, the
// adjoint to inputs and parameters (parameter gradients reduced without atomics), and streamed
// inference over batches of any size. Tensors in and out are sample-major rows padded to 4 floats
// (see mlp_config.hpp); the hidden activations and gradients inside a Workspace are lane-
// interleaved in groups of 8 samples (shaders/include/nf_rows.glsl). Shaders: shaders/nn/mlp_*.comp.
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
  std::uint32_t input_stride() const { return layers_.front().in_stride; }
  std::uint32_t output_stride() const { return layers_.back().out_stride; }
  gpu::Buffer<float>& parameters() { return *parameters_; }
  const gpu::Buffer<float>& parameters() const { return *parameters_; }
  gpu::Buffer<float>& gradients() { return *gradients_; }

  // What a training step keeps between forward and backward, sized for one batch.
  class Workspace {
   public:
    Workspace(const Mlp& mlp, std::uint32_t batch);
    std::uint32_t batch() const { return batch_; }
    // The network output of the last forward: [batch][output_stride].
    gpu::BufferRange output() const { return y_.back()->whole(); }

   private:
    friend class Mlp;
    // What layer li's activation derivative is taken from: its output, its pre-activation for Sine.
    gpu::BufferRange kept(std::size_t li) const { return (z_[li] ? z_[li] : y_[li])->whole(); }
    std::uint32_t batch_;
    std::vector<std::unique_ptr<gpu::Buffer<float>>> y_, z_;  // per layer; z_ only for Sine layers
    std::unique_ptr<gpu::Buffer<float>> grad_a_, grad_b_, grad_zt_, partials_, transposed_;
  };

  // Records the training forward of `input` ([batch][input_stride]) into the workspace.
  void forward(gpu::Stream& stream, Workspace& workspace, gpu::BufferRange input) const;

  // Records the adjoint. grad_output: [batch][output_stride]. Parameter gradients are written to
  // gradients() (added when `accumulate`). grad_input, when not empty, receives dL/dinput
  // ([batch][input_stride]).
  void backward(gpu::Stream& stream, Workspace& workspace, gpu::BufferRange input, gpu::BufferRange grad_output,
                gpu::BufferRange grad_input, bool accumulate);

  // Records inference of `input` ([batch][input_stride]) into `output` ([batch][output_stride]) in
  // chunks that fit the device's bindings and a bounded scratch.
  void infer(gpu::Stream& stream, gpu::BufferRange input, gpu::BufferRange output, std::uint64_t batch) const;

  // Floating-point work per sample (multiply-adds count 2), without the padding.
  double forward_flops_per_sample() const;
  double backward_flops_per_sample() const;

 private:
  // y = act(W x + b) for W of out_dim rows of in_stride floats stored in `weights` from weight_offset.
  struct Product {
    const gpu::RawBuffer* weights;
    std::uint64_t weight_offset;  // floats
    std::uint32_t in_stride, out_dim, out_stride;
    gpu::BufferRange biases;  // empty: no bias
    ActivationSpec activation;
  };
  // Layouts of x and of y (and z): 1 = lane-interleaved (hidden tensors), 0 = sample-major.
  struct Layouts {
    std::uint32_t x_interleaved, y_interleaved;
  };
  // The input adjoint's epilogue for a hidden layer below (mlp_fwd.comp, ADJOINT): the product
  // times that layer's activation derivative, written as its dz and, transposed, as its dz^T.
  struct AdjointEpilogue {
    gpu::BufferRange below;  // the layer's output (pre-activation for Sine); empty: no epilogue
    ActivationSpec activation;
    gpu::BufferRange transposed;  // [out][zt_stride]
    std::uint32_t zt_stride = 0;
  };
  void record_product(gpu::Stream& stream, const Product& product, gpu::BufferRange x, gpu::BufferRange y,
                      gpu::BufferRange z, std::uint32_t batch, Layouts layouts, const AdjointEpilogue& adjoint) const;
  void record_layer_forward(gpu::Stream& stream, const LayerShape& layer, gpu::BufferRange x, gpu::BufferRange y,
                            gpu::BufferRange z, std::uint32_t batch, Layouts layouts) const;
  // Input vec4 per mlp_fwd dispatch on this device (its weight block fills shared memory).
  std::uint32_t forward_chunk4() const;
  // mlp_weights_bwd' samples per slab / 4 on this device (its input block fills shared
  // memory), and the slabs of a batch.
  std::uint32_t slab4() const;
  std::uint32_t slabs(std::uint32_t batch) const;
  // The device's workgroup size limit, capped at `most`, in whole groups of 8 lanes.
  std::uint32_t workgroup_limit(std::uint32_t most) const;

  gpu::Context& context_;
  MlpConfig config_;
  std::vector<LayerShape> layers_;
  std::unique_ptr<gpu::Buffer<float>> parameters_, gradients_;
};

}  // namespace nf::nn
