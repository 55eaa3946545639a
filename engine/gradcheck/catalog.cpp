#include "engine/gradcheck/catalog.hpp"

#include "engine/fur/fur_field_head_gradcheck.hpp"
#include "engine/fur/length_factors_gradcheck.hpp"
#include "engine/fur/strand_geometry_gradcheck.hpp"
#include "engine/fur/strand_chamfer_gradcheck.hpp"
#include "engine/fur/strand_losses_gradcheck.hpp"
#include "engine/nn/encoding_gradcheck.hpp"
#include "engine/nn/loss_gradcheck.hpp"
#include "engine/nn/mlp_gradcheck.hpp"
#include "engine/neus/volume_render_gradcheck.hpp"
#include "engine/splat/rasterizer_gradcheck.hpp"
#include "engine/splat/image_losses_gradcheck.hpp"
#include "engine/splat/segment_gaussian_gradcheck.hpp"

namespace nf::gradcheck {

std::vector<std::unique_ptr<DifferentiableKernel>> all_kernels() {
  std::vector<std::unique_ptr<DifferentiableKernel>> kernels;
  kernels.push_back(nn::make_mlp_check());
  kernels.push_back(nn::make_frequency_encoding_check());
  kernels.push_back(nn::make_hash_grid_check());
  kernels.push_back(nn::make_mse_loss_check());
  kernels.push_back(splat::make_segment_gaussian_check());
  kernels.push_back(splat::make_image_losses_check());
  kernels.push_back(splat::make_rasterizer_check());
  kernels.push_back(neus::make_volume_render_check());
  kernels.push_back(fur::make_strand_geometry_check());
  kernels.push_back(fur::make_strand_losses_check());
  kernels.push_back(fur::make_strand_chamfer_check());
  kernels.push_back(fur::make_fur_head_check());
  kernels.push_back(fur::make_length_factors_check());
  return kernels;
}

}  // namespace nf::gradcheck
