#pragma once
// Non-bald masks (paper: the silhouette and orientation losses are masked to where fur grows):
// per camera, M_NeuS rendered with 1 where the region of the surface seen at the pixel grows fur
// and 0 where it is bald (eyes, nose tip, paw pads, any zero-length region) or where the pixel
// misses the animal. The seen point comes from the GPU depth map (geometry/mesh_depth.hpp), its
// region from the nearest labelled vertex.
#include <filesystem>
#include <vector>

#include "engine/geometry/mesh.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::defur {

struct MaskStats {
  std::uint64_t pixels = 0, animal = 0, fur = 0;  // all pixels, pixels on the animal, on fur
};

// One 1-channel image per camera of `views` (values 0 or 1). labelled: M_NeuS with regions.
std::vector<io::Image> nonbald_masks(gpu::Context& gpu, const geometry::Mesh& labelled, const knowledge::Knowledge& knowledge,
                                     const io::Scene& scene, const std::vector<std::uint32_t>& views, MaskStats* stats = nullptr);

// The depth map of a mesh seen from a scene camera (+inf where no triangle is hit).
std::vector<float> camera_depth(gpu::Context& gpu, const geometry::Mesh& mesh, const io::Camera& camera);

}  // namespace nf::defur
