#include "engine/defur/nonbald_masks.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_depth.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::defur {

std::vector<float> camera_depth(gpu::Context& gpu, const geometry::Mesh& mesh, const io::Camera& camera) {
  return geometry::mesh_depth(gpu, geometry::depth_camera(camera), mesh.positions, mesh.triangles);
}

std::vector<io::Image> nonbald_masks(gpu::Context& gpu, const geometry::Mesh& labelled, const knowledge::Knowledge& knowledge,
                                     const io::Scene& scene, const std::vector<std::uint32_t>& views, MaskStats* stats) {
  NF_CHECK(labelled.regions.size() == labelled.vertex_count(), "nonbald_masks: a region per vertex");
  for (std::size_t v = 0; v < labelled.regions.size(); ++v)
    if (labelled.regions[v] < 0 || labelled.regions[v] >= body::kRegionCount)
      throw InputError("non-bald masks: vertex " + std::to_string(v) + " has region id " + std::to_string(labelled.regions[v]) +
                       ", outside the table");
  for (std::uint32_t view : views)
    if (view >= scene.cameras.size()) throw InputError("non-bald masks: no camera " + std::to_string(view));
  const geometry::PointIndex index(labelled.positions);
  std::vector<io::Image> masks;
  MaskStats total;
  for (std::uint32_t view : views) {
    const io::Camera& cam = scene.cameras[view];
    const std::vector<float> depth = camera_depth(gpu, labelled, cam);
    io::Image mask{cam.width, cam.height, 1, std::vector<float>(std::size_t(cam.width) * cam.height, 0.f)};
    std::vector<std::uint64_t> animal(cam.height, 0), fur(cam.height, 0);
    parallel_for(cam.height, [&](std::size_t y0, std::size_t y1) {
      for (std::size_t y = y0; y < y1; ++y)
        for (std::uint32_t x = 0; x < cam.width; ++x) {
          const float d = depth[y * cam.width + x];
          if (!std::isfinite(d)) continue;
          ++animal[y];
          const glm::dvec3 world = cam.unproject({double(x) + 0.5, double(y) + 0.5}, double(d));
          const float q[3]{float(world.x), float(world.y), float(world.z)};
          const std::uint32_t v = index.nearest(q).first;
          if (knowledge.grows_fur(body::Region(labelled.regions[v]))) mask.pixels[y * cam.width + x] = 1.f, ++fur[y];
        }
    }, 1);
    total.pixels += std::uint64_t(cam.width) * cam.height;
    for (std::uint32_t y = 0; y < cam.height; ++y) total.animal += animal[y], total.fur += fur[y];
    masks.push_back(std::move(mask));
  }
  if (stats) *stats = total;
  return masks;
}

}  // namespace nf::defur
