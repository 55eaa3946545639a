#pragma once
// Previews of the surface stage for people to look at, and the held-out PSNR: per view, the
// extracted mesh's depth (GPU raster, geometry/mesh_depth) gives the surface point of every pixel;
// the field gives its colour (seen along the pixel's ray) and normal there. Writes
// <out>/<camera>_{rgb,normal,depth}.png and <camera>_depth.exr (depth along the camera axis,
// 0 where the mesh does not cover the pixel).
#include <filesystem>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/mesh.hpp"
#include "engine/neus/neus_field.hpp"
#include "engine/neus/neus_trainer.hpp"

namespace nf::neus {

// Returns per view {camera, psnr_in_mask, silhouette_iou (mesh coverage against the mask), pixels
// covered by the mesh outside the mask and mask pixels it misses} and the mean PSNR over the views (colours in [0, 1],
// pixels inside the view's mask; pixels the mesh misses count as black).
json render_neus_previews(NeusField& field, const NeusTrainingData& data, const geometry::Mesh& mesh,
                          const std::vector<std::uint32_t>& views, float finite_difference_step,
                          const std::filesystem::path& out);

}  // namespace nf::neus
