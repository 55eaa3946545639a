#include "engine/orient/scene_orientation.hpp"

#include "engine/core/output_guard.hpp"
#include "engine/core/progress.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/view_names.hpp"
#include "engine/orient/orientation_io.hpp"
#include "engine/orient/orientation_map.hpp"

namespace nf::orient {

std::vector<std::filesystem::path> write_scene_orientations(gpu::Context& context, const SceneOrientationOptions& o) {
  const io::Scene scene = io::read_scene(o.scene);
  scene.check_files(o.scene.string());
  refuse_output_inside(o.out, scene.root, "--out", "scene");
  const std::vector<std::uint32_t> views = io::parse_view_list(o.views, scene.cameras.size());
  const std::vector<std::string> names = io::view_file_names(scene, views);
  OutputFolder folder(o.out, "orient");
  std::vector<std::filesystem::path> files;
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
    progress.update(k + 1, cam.name);
  }
  progress.finish();
  folder.finish();  // one result per folder: an earlier run's other views go
  return files;
}

}  // namespace nf::orient
