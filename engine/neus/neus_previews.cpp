#include "engine/neus/neus_previews.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/geometry/mesh_depth.hpp"
#include "engine/io/image.hpp"

namespace nf::neus {

json render_neus_previews(NeusField& field, const NeusTrainingData& data, const geometry::Mesh& mesh,
                          const std::vector<std::uint32_t>& views, float h, const std::filesystem::path& out) {
  std::filesystem::create_directories(out);
  json per_view = json::array();
  double psnr_sum = 0;
  int psnr_views = 0;
  for (const std::uint32_t v : views) {
    const io::Camera& cam = data.scene.cameras[v];
    const std::size_t pixels = std::size_t(cam.width) * cam.height;
    const std::vector<float> depth = mesh.triangle_count() == 0
                                         ? std::vector<float>(pixels, geometry::kNoDepth)
                                         : geometry::mesh_depth(field.context(), geometry::depth_camera(cam, 1e-4f),
                                                                mesh.positions, mesh.triangles);
    std::vector<glm::vec3> points, dirs;
    std::vector<std::size_t> where;
    const glm::dvec3 eye = cam.centre();
    for (std::size_t p = 0; p < pixels; ++p) {
      if (!std::isfinite(depth[p])) continue;
      const double x = double(p % cam.width) + 0.5, y = double(p / cam.width) + 0.5;
      const glm::dvec3 world = cam.unproject({x, y}, double(depth[p]));
      points.push_back(glm::vec3(data.norm.to_unit(world)));
      dirs.push_back(glm::vec3(glm::normalize(world - eye)));
      where.push_back(p);
    }
    const NeusField::Shading shading = field.shade(points, dirs, h);
    io::Image rgb{cam.width, cam.height, 3, std::vector<float>(pixels * 3, 0.f)};
    io::Image normal{cam.width, cam.height, 3, std::vector<float>(pixels * 3, 0.f)};
    io::Image depth_png{cam.width, cam.height, 1, std::vector<float>(pixels, 0.f)};
    io::Image depth_exr{cam.width, cam.height, 1, std::vector<float>(pixels, 0.f)};
    float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
    for (const std::size_t p : where) lo = std::min(lo, depth[p]), hi = std::max(hi, depth[p]);
    for (std::size_t i = 0; i < where.size(); ++i) {
      const std::size_t p = where[i];
      const glm::vec3 n = glm::length(shading.gradient[i]) > 0 ? glm::normalize(shading.gradient[i]) : glm::vec3(0.f);
      for (int c = 0; c < 3; ++c) {
        rgb.pixels[p * 3 + c] = shading.rgb[i][c];
        normal.pixels[p * 3 + c] = 0.5f * (n[c] + 1.f);
      }
      depth_exr.pixels[p] = depth[p];
      depth_png.pixels[p] = hi > lo ? 1.f - 0.8f * (depth[p] - lo) / (hi - lo) : 1.f;  // near is bright
    }
    const std::string stem = cam.name.empty() ? std::to_string(v) : cam.name;
    io::write_png(out / (stem + "_rgb.png"), rgb);
    io::write_png(out / (stem + "_normal.png"), normal);
    io::write_png(out / (stem + "_depth.png"), depth_png);
    io::write_exr(out / (stem + "_depth.exr"), depth_exr);
    json entry{{"camera", cam.name}, {"index", v}, {"covered_pixels", where.size()}};
    const std::vector<std::uint8_t>& mask = data.masks[v];
    const std::vector<std::uint8_t>& truth = data.rgb[v];
    if (!mask.empty()) {  // the mesh's silhouette against the mask
      std::size_t both = 0, mesh_only = 0, mask_only = 0;
      for (std::size_t p = 0; p < pixels; ++p) {
        const bool m = mask[p] != 0, c = std::isfinite(depth[p]);
        both += m && c, mesh_only += c && !m, mask_only += m && !c;
      }
      entry["silhouette_iou"] = double(both) / double(std::max<std::size_t>(1, both + mesh_only + mask_only));
      entry["mesh_outside_mask_px"] = mesh_only;
      entry["mask_not_covered_px"] = mask_only;
    }
    if (!mask.empty() && !truth.empty()) {
      double se = 0;
      std::size_t count = 0;
      for (std::size_t p = 0; p < pixels; ++p) {
        if (!mask[p]) continue;
        for (int c = 0; c < 3; ++c) {
          const double e = double(rgb.pixels[p * 3 + c]) - truth[p * 3 + c] / 255.0;
          se += e * e;
        }
        ++count;
      }
      if (count > 0 && se > 0) {
        const double psnr = -10.0 * std::log10(se / (3.0 * count));
        entry["psnr_in_mask"] = psnr;
        psnr_sum += psnr, ++psnr_views;
      }
    }
    per_view.push_back(entry);
  }
  json result{{"views", per_view}};
  if (psnr_views > 0) result["psnr_in_mask_mean"] = psnr_sum / psnr_views;
  return result;
}

}  // namespace nf::neus
