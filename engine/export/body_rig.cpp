#include "engine/export/body_rig.hpp"

#include <algorithm>
#include <array>
#include <map>

#include "engine/body/posing.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/surface_locator.hpp"

namespace nf::exporter {
namespace {

struct Posed {
  body::PoseTrace trace;
  glm::dmat4 fit_to_world;
  glm::dvec3 world(const glm::dvec3& animal) const {
    const glm::dvec3 fit = trace.scale * (trace.rotation * animal) + trace.translation;
    return glm::dvec3(fit_to_world * glm::dvec4(fit, 1.0));
  }
};

Posed pose(const body::BodyModel& model, const body::BodyFit& fit) {
  const body::PoseLayout layout = body::PoseLayout::of(model, true);
  return {body::pose_forward(model, layout, fit.variables), fit.fit_to_world};
}

}  // namespace

geometry::Mesh fitted_body_world(const body::BodyModel& model, const body::BodyFit& fit) {
  const Posed p = pose(model, fit);
  geometry::Mesh m;
  m.triangles = model.triangles;
  m.regions = model.regions;
  m.positions.resize(3 * model.vertex_count());
  for (std::size_t v = 0; v < model.vertex_count(); ++v) {
    const glm::dvec3 w = p.world(p.trace.animal[v]);
    for (int a = 0; a < 3; ++a) m.positions[3 * v + std::size_t(a)] = float(w[a]);
  }
  geometry::compute_vertex_normals(m);
  return m;
}

io::Skeleton transfer_rig(const body::BodyModel& model, const body::BodyFit& fit, const geometry::Mesh& surface_world,
                          const ExportFrame& frame) {
  const Posed p = pose(model, fit);
  io::Skeleton s;
  s.joint_names = model.joint_names;
  s.parents = model.parents;
  for (std::size_t j = 0; j < model.joint_count(); ++j)
    s.joint_positions.push_back(frame.point(glm::vec3(p.world(glm::dvec3(p.trace.global[j][3])))));
  const geometry::Mesh body = fitted_body_world(model, fit);
  const geometry::SurfaceLocator locator(body);
  const std::size_t V = surface_world.vertex_count();
  s.skin_joints.assign(io::kJointInfluences * V, 0);
  s.skin_weights.assign(io::kJointInfluences * V, 0.f);
  parallel_for(V, [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v) {
      const geometry::SurfaceHit hit = locator.closest(surface_world.position(v));
      constexpr std::size_t kMax = 3 * body::kSkinInfluences;
      std::array<float, kMax> weight{};
      std::array<std::uint32_t, kMax> joint{};
      std::size_t n = 0;
      for (int c = 0; c < 3; ++c) {
        const std::size_t corner = body.triangles[3 * std::size_t(hit.face) + std::size_t(c)];
        for (int k = 0; k < body::kSkinInfluences; ++k) {
          const float wk = hit.barycentric[c] * model.skin_weights[corner * body::kSkinInfluences + std::size_t(k)];
          const std::uint32_t jk = model.skin_joints[corner * body::kSkinInfluences + std::size_t(k)];
          if (wk <= 0) continue;
          std::size_t i = 0;
          while (i < n && joint[i] != jk) ++i;
          if (i == n && n < kMax) joint[n] = jk, weight[n] = 0.f, ++n;
          if (i < n) weight[i] += wk;
        }
      }
      // The largest first (selection: n is at most 12).
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = i + 1; k < n; ++k)
          if (weight[k] > weight[i]) std::swap(weight[i], weight[k]), std::swap(joint[i], joint[k]);
      n = std::min<std::size_t>(n, io::kJointInfluences);
      float total = 0;
      for (std::size_t i = 0; i < n; ++i) total += weight[i];
      if (!(total > 0)) {  // cannot happen with valid model weights; bind to the root rather than fail
        s.skin_weights[io::kJointInfluences * v] = 1.f;
        continue;
      }
      for (std::size_t i = 0; i < n; ++i) {
        s.skin_joints[io::kJointInfluences * v + i] = std::uint16_t(joint[i]);
        s.skin_weights[io::kJointInfluences * v + i] = weight[i] / total;
      }
    }
  });
  return s;
}

}  // namespace nf::exporter
