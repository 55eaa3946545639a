#include "engine/orient/scene_orientation.hpp"

#include "engine/core/output_guard.hpp"
#include "engine/core/progress.hpp"
#include <optional>

#include "engine/core/atomic_file.hpp"
#include "engine/core/json.hpp"
#include "engine/core/log.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/view_names.hpp"
#include "engine/orient/orientation_io.hpp"
#include "engine/orient/orientation_map.hpp"
#include "engine/orient/orientation_scales.hpp"

namespace nf::orient {

SceneOrientations write_scene_orientations(gpu::Context& context, const SceneOrientationOptions& o) {
  const io::Scene scene = io::read_scene(o.scene);
  scene.check_files(o.scene.string());
  refuse_output_inside(o.out, scene.root, "--out", "scene");
  const std::vector<std::uint32_t> views = io::parse_view_list(o.views, scene.cameras.size());
  const std::vector<std::string> names = io::view_file_names(scene, views);
  OutputFolder folder(o.out, "orient");
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(scene.root);
  SceneOrientations result;
  std::vector<std::filesystem::path>& files = result.files;
  json agreement = json::array();
  Progress progress("orient", views.size());
  for (std::size_t k = 0; k < views.size(); ++k) {
    const io::Camera& cam = scene.cameras[views[k]];
    const io::Image photo = io::read_image(cam.image);
    std::vector<std::uint8_t> mask;
    if (!cam.mask.empty()) mask = io::mask_of(io::read_image(cam.mask));
    const OrientationMap map = gabor_orientation(context, photo, cam.mask.empty() ? nullptr : &mask, o.gabor);
    files.push_back(folder.claim(names[k] + ".exr"));
    write_orientation_exr(files.back(), map);
    files.push_back(folder.claim(names[k] + ".png"));
    write_orientation_png(files.back(), map);
    if (gt && std::filesystem::exists(gt->orientation(cam.name))) {
      const OrientationMap truth = read_orientation_exr(gt->orientation(cam.name));
      if (mask.empty()) mask.assign(std::size_t(photo.width) * photo.height, 1);
      const TruthAgreement a = agreement_with_truth(map, orientation_reliability(map, o.reliability_window), truth, mask);
      if (a.pixels == 0) {
        log::warn("orient: camera '", cam.name, "' shows no strand away from its outline; not scored against the truth");
        continue;
      }
      result.truth.push_back({cam.name, a});
      agreement.push_back({{"camera", cam.name}, {"pixels", a.pixels}, {"median_error_deg", a.median_error_deg},
                           {"reliable_share", a.reliable_share}, {"median_error_reliable_deg", a.median_error_reliable_deg},
                           {"weighted_error_deg", a.weighted_error_deg}, {"mean_reliability", a.mean_reliability},
                           {"median_error_by_reliability_deg", a.median_error_by_reliability}, {"share_by_reliability", a.share_by_reliability}});
    }
    progress.update(k + 1, cam.name);
  }
  progress.finish();
  if (!agreement.empty()) {
    files.push_back(folder.claim("truth_agreement.json"));
    write_file_atomic(files.back(), json{{"views", agreement}, {"reliability_window", o.reliability_window}}.dump(2) + "\n");
  }
  folder.finish();  // one result per folder: an earlier run's other views go
  return result;
}

}  // namespace nf::orient
