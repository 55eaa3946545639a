#include "engine/prepare/prepare_scene.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/io/image.hpp"
#include "engine/io/image_size.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/auto_masks.hpp"
#include "engine/prepare/colmap_command.hpp"
#include "engine/prepare/colmap_models.hpp"
#include "engine/prepare/floor_consistency.hpp"
#include "engine/prepare/known_distance.hpp"
#include "engine/prepare/photo_mats.hpp"
#include "engine/prepare/scene_layout.hpp"
#include "engine/prepare/silhouette_check.hpp"
#include "engine/prepare/sparse_points.hpp"
#include "engine/prepare/video_frames.hpp"

namespace nf::prepare {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMinPhotos = 8;  // fewer cannot show an animal all round; COLMAP itself needs 3
constexpr std::size_t kExhaustiveLimit = 150;  // beyond it, exhaustive matching's pairs take hours on a laptop

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_photo(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// The mask file of a photo in the user's mask folder: <stem>.png, or the photo's own name.
fs::path mask_file(const fs::path& masks, const fs::path& photo) {
  for (const fs::path& candidate : {masks / (photo.stem().string() + ".png"), masks / photo.filename(),
                                    masks / (photo.stem().string() + ".jpg"), masks / (photo.filename().string() + ".png")})
    if (fs::is_regular_file(candidate)) return candidate;
  return {};
}

// The mean reprojection error and the number of points of a text model's points3D.txt.
std::pair<double, std::uint64_t> point_statistics(const fs::path& model) {
  std::ifstream in(model / "points3D.txt");
  double sum = 0;
  std::uint64_t n = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    double id, x, y, z, r, g, b, error;
    if (words >> id >> x >> y >> z >> r >> g >> b >> error) sum += error, ++n;
  }
  return {n ? sum / double(n) : 0.0, n};
}

class Steps {
 public:
  explicit Steps(json& report) : report_(report) {}
  void add(const std::string& name, double seconds) {
    report_["seconds"][name] = seconds;
    total_ += seconds;
    report_["seconds"]["total"] = total_;
  }

 private:
  json& report_;
  double total_ = 0;
};

// The photo with its mask's outline in red, to check a mask at a glance.
void write_outline_preview(const fs::path& file, const io::Camera& camera, const std::vector<std::uint8_t>& inside) {
  // At most kWorkingSide on the longer side: a one-pixel outline on a 12 MP photo vanishes when the
  // preview is looked at whole.
  const io::Camera shown = io::reduced_to(camera, kWorkingSide);
  const cv::Mat photo = photo_bgr(shown);
  cv::Mat mask(int(camera.height), int(camera.width), CV_8U, const_cast<std::uint8_t*>(inside.data()));
  if (shown.width != camera.width) {
    cv::Mat reduced;
    cv::resize(mask * 255, reduced, photo.size(), 0, 0, cv::INTER_AREA);
    mask = reduced >= 128;
  }
  const std::uint32_t w = shown.width, h = shown.height;
  io::Image rgb{w, h, 3, std::vector<float>(std::size_t(w) * h * 3)};
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      const bool in = mask.at<std::uint8_t>(int(y), int(x)) != 0;
      const bool edge = (x > 0 && (mask.at<std::uint8_t>(int(y), int(x) - 1) != 0) != in) || (y > 0 && (mask.at<std::uint8_t>(int(y) - 1, int(x)) != 0) != in);
      const cv::Vec3b& px = photo.at<cv::Vec3b>(int(y), int(x));
      for (std::uint32_t c = 0; c < 3; ++c) rgb.pixels[3 * (std::size_t(y) * w + x) + c] = edge ? (c == 0 ? 1.f : 0.f) : float(px[2 - c]) / 255.f;
    }
  write_file_atomic(file, io::encode_jpeg(rgb, 90));
}

// cameras.txt's cameras: model, size and parameters (focal lengths, principal point, distortion).
json camera_lines(const fs::path& file) {
  json cameras = json::array();
  for (const auto& [id, lens] : read_colmap_cameras(file))
    cameras.push_back({{"model", lens.model}, {"width", lens.width}, {"height", lens.height}, {"params", lens.params}});
  return cameras;
}

// The photos in a folder, sorted by name (the order sequential matching follows); other files are
// named in a warning.
std::vector<fs::path> list_photos(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw InputError("prepare: --images " + folder.string() + " is not a folder");
  std::vector<fs::path> photos;
  std::vector<std::string> skipped;
  for (const fs::directory_entry& e : fs::directory_iterator(folder)) {
    if (!e.is_regular_file()) continue;
    if (is_photo(e.path())) photos.push_back(e.path());
    else skipped.push_back(e.path().filename().string());
  }
  std::sort(photos.begin(), photos.end());
  std::sort(skipped.begin(), skipped.end());
  const std::string some_skipped = skipped.empty() ? "" : skipped.front() + (skipped.size() > 1 ? ", ..." : "");
  if (photos.size() < kMinPhotos)
    throw InputError("prepare: " + std::to_string(photos.size()) + " PNG or JPEG photo(s) in " + folder.string() +
                     (skipped.empty() ? "" : " (besides " + std::to_string(skipped.size()) + " other file(s): " + some_skipped + ")") +
                     "; prepare needs at least " + std::to_string(kMinPhotos) + ", and a good scene 30-80 photos taken in a circle around the animal");
  if (!skipped.empty()) log::warn("prepare: ", skipped.size(), " file(s) in ", folder.string(), " are not PNG or JPEG photos and are left out (", some_skipped, ")");
  return photos;
}

double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

json prepare_scene(const PrepareOptions& o) {
  // Everything the user can get wrong is checked before COLMAP runs for minutes.
  const bool from_video = !o.video.empty();
  if (from_video == !o.images.empty()) throw UsageError("prepare: give the photos (--images DIR) or a video (--video FILE), one of them");
  if (from_video && !o.masks.empty()) throw UsageError("prepare: --masks goes with --images; a video's frames are chosen here, and their masks made here");
  if (from_video && !o.colmap_model.empty()) throw UsageError("prepare: --colmap goes with --images (the photos the model was made from)");
  if (from_video && !fs::is_regular_file(o.video)) throw InputError("prepare: --video " + o.video.string() + " is not a file");
  if (o.cm_per_unit && !o.known_distance.empty()) throw UsageError("prepare: --scene-scale and --known-distance both set the unit; give one");
  const std::uint32_t working_side = o.working_side ? o.working_side : kWorkingSide;
  std::optional<KnownDistance> known;
  if (!o.known_distance.empty()) known = read_known_distance(o.known_distance);
  // The tools are found before anything runs for minutes.
  if (o.colmap_model.empty()) colmap_executable();
  if (from_video) video_tools();
  std::vector<fs::path> photos;
  if (!from_video) {
    photos = list_photos(o.images);
    for (const fs::path& p : photos) io::require_complete_image(p);  // truncated photos are named now, not by COLMAP
    for (std::size_t i = 0; known && i < known->points.size(); ++i)
      for (const auto& [name, pixel] : known->points[i]) {
        const auto photo = std::find_if(photos.begin(), photos.end(), [&](const fs::path& p) { return p.filename() == name; });
        if (photo == photos.end())
          throw InputError("--known-distance " + o.known_distance.string() + ": points[" + std::to_string(i) + "] names " + name + ", which is not a photo in " + o.images.string());
        const auto [w, h] = io::image_size(*photo);
        if (!(pixel.x >= 0 && pixel.y >= 0 && pixel.x < w && pixel.y < h))
          throw InputError("--known-distance " + o.known_distance.string() + ": points[" + std::to_string(i) + "][\"" + name + "\"] lies outside the photo (" +
                           std::to_string(w) + "x" + std::to_string(h) + ")");
      }
  }

  // Masks: the user's, the photos' alpha, or (when a photo has neither) made here once the cameras are known.
  // A video's frames (decoded here, after this) have no alpha.
  const bool automatic = from_video || (o.masks.empty() && std::any_of(photos.begin(), photos.end(), [](const fs::path& p) {
    const std::uint32_t channels = io::image_channels(p);
    return channels != 2 && channels != 4;
  }));
  std::map<std::string, io::Image> masks;  // by photo name, one channel
  for (const fs::path& p : automatic ? std::vector<fs::path>() : photos) {
    fs::path file = p;
    if (!o.masks.empty()) {
      file = mask_file(o.masks, p);
      if (file.empty()) throw InputError("prepare: no mask for " + p.filename().string() + " in " + o.masks.string() + " (looked for " + p.stem().string() + ".png and " + p.filename().string() + ")");
    }
    const io::Image image = io::read_image(file);
    if (const auto [w, h] = io::image_size(p); image.width != w || image.height != h)
      throw InputError("prepare: mask " + file.string() + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", its photo " +
                       std::to_string(w) + "x" + std::to_string(h));
    const std::vector<std::uint8_t> inside = io::mask_of(image);
    io::Image m{image.width, image.height, 1, std::vector<float>(inside.begin(), inside.end())};
    masks[p.filename().string()] = std::move(m);
  }

  const fs::path out = fs::absolute(o.out).lexically_normal();
  if (fs::exists(out)) throw UsageError("prepare: --out " + out.string() + " exists; name a new folder (nothing there is replaced)");
  if (!from_video) refuse_output_inside(out, o.images, "--out", "photos");
  if (!o.masks.empty()) refuse_output_inside(out, o.masks, "--out", "masks");
  const fs::path work = out.parent_path() / (out.filename().string() + ".partial");
  // Inputs left in an earlier run's scratch folder (a video's frames, COLMAP's models) would be
  // cleared with it.
  for (const auto& [input, flag] : {std::pair{o.colmap_model, "--colmap"}, std::pair{o.images, "--images"}, std::pair{o.masks, "--masks"}})
    if (!input.empty() && (fs::absolute(input).lexically_normal().string() + "/").rfind(work.string() + "/", 0) == 0)
      throw UsageError(std::string("prepare: ") + flag + " " + input.string() + " lies in " + work.string() + ", which this run clears: choose another --out");
  fs::remove_all(work);
  create_output_folder(work / "colmap", "--out");
  const fs::path log_file = work / "colmap" / "colmap.log";

  json report;
  fs::path images = o.images;
  if (from_video) {
    images = work / "colmap" / "frames";  // kept: --images for a later --colmap run on the same model
    report["video"] = extract_video_frames({o.video, images, o.video_frames, 4, log_file});
    photos = list_photos(images);
  }
  report["photos"] = photos.size();
  report["masks"] = automatic ? "automatic" : o.masks.empty() ? "alpha" : "given";
  Steps steps(report);
  const fs::path database = work / "colmap" / "database.db";
  fs::path model = o.colmap_model;
  if (model.empty()) {
    steps.add("features", run_colmap("feature_extractor", {"--database_path", database.string(), "--image_path", images.string(),
                                                          "--ImageReader.single_camera", "1", "--ImageReader.camera_model", "SIMPLE_RADIAL",
                                                          "--SiftExtraction.use_gpu", "0", "--SiftExtraction.max_num_features", std::to_string(o.max_features)},
                                     log_file));
    // Exhaustive matching finds the loop a circle closes; beyond a few hundred photos its pairs take
    // hours, and the photos' order (a video's, or a camera's file names) says which are neighbours.
    const bool exhaustive = photos.size() <= kExhaustiveLimit;
    report["matching"] = exhaustive ? "exhaustive" : "sequential";
    steps.add("matching", exhaustive ? run_colmap("exhaustive_matcher", {"--database_path", database.string(), "--SiftMatching.use_gpu", "0"}, log_file)
                                     : run_colmap("sequential_matcher", {"--database_path", database.string(), "--SiftMatching.use_gpu", "0",
                                                                         "--SequentialMatching.overlap", "20", "--SequentialMatching.quadratic_overlap", "1"},
                                                  log_file));
    const fs::path sparse = work / "colmap" / "sparse";
    fs::create_directories(sparse);
    // COLMAP's threads make each run differ a little (its SIFT descriptors change by a few bytes, its
    // mapper draws random samples in whatever order its threads run). One mapper thread made the
    // same database give the same cameras, but one run of four on it placed a photo 2.8 radii off,
    // where the threaded mapper had placed every photo in six; so the threads stay.
    steps.add("mapping", run_colmap("mapper", {"--database_path", database.string(), "--image_path", images.string(), "--output_path", sparse.string()}, log_file));
    // COLMAP writes one model per connected group of photos; the largest is the animal, unless two are alike.
    const std::vector<ColmapModel> models = read_colmap_models(sparse);
    model = choose_colmap_model(models, kMinPhotos, log_file).folder;
    report["colmap_models"] = models.size();
  } else if (!fs::exists(model / "images.bin") && !fs::exists(model / "images.txt")) {
    throw InputError("prepare: --colmap " + model.string() + " holds no COLMAP model (images.bin or images.txt)");
  }

  // Undistorted pinhole photos and masks: the same undistortion applied to both.
  const fs::path undistorted = work / "colmap" / "undistorted", mask_input = work / "colmap" / "mask_input",
                 undistorted_masks = work / "colmap" / "undistorted_masks";
  auto start = std::chrono::steady_clock::now();
  fs::create_directories(mask_input);
  for (const auto& [name, m] : masks) {
    // Named like its photo (COLMAP finds images by name) with PNG content, which it detects.
    io::write_png(mask_input / name, m);
  }
  if (!automatic) steps.add("masks_staged", since(start));
  // At the photo's own size and principal point (scale 1): COLMAP's default crops to the pixels
  // the lens fills, and an odd crop (511 of 512, the centre at 255.5) resamples every pixel half
  // a pixel off, which blurred the masks' outline (the user's masks' IoU 0.97 against 0.999 when
  // the crop was even). A strong lens leaves blank pixels at the corners instead.
  const std::vector<std::string> same_grid{"--output_type", "COLMAP", "--min_scale", "1", "--max_scale", "1"};
  const auto undistort = [&](const fs::path& from, const fs::path& to) {
    std::vector<std::string> args{"--image_path", from.string(), "--input_path", model.string(), "--output_path", to.string()};
    args.insert(args.end(), same_grid.begin(), same_grid.end());
    return run_colmap("image_undistorter", args, log_file);
  };
  steps.add("undistort", undistort(images, undistorted));
  if (!automatic) steps.add("undistort_masks", undistort(mask_input, undistorted_masks));
  steps.add("model_text", run_colmap("model_converter", {"--input_path", (undistorted / "sparse").string(), "--output_path", undistorted.string(), "--output_type", "TXT"}, log_file));
  // The lens COLMAP found (before undistortion): the user's check that the focal length is sane.
  const fs::path lens = work / "colmap" / "lens";
  fs::create_directories(lens);
  steps.add("lens", run_colmap("model_converter", {"--input_path", model.string(), "--output_path", lens.string(), "--output_type", "TXT"}, log_file));
  report["cameras"] = camera_lines(lens / "cameras.txt");
  const std::map<std::string, Lens> lenses = read_lenses(lens);
  fs::remove_all(lens);

  start = std::chrono::steady_clock::now();
  io::Scene scene = io::read_colmap_scene(undistorted);
  const SparsePoints sparse = read_sparse_points(undistorted);
  SceneLayout layout = find_layout(scene.cameras, sparse);
  // Cameras COLMAP put where no photo of the animal was taken are left out (they would mislead the
  // masks and every stage after), then the layout is found again without them.
  // A video's frames (named in time order) lie on one path: a frame off it is misplaced even when
  // it aims at the animal.
  if (from_video) std::sort(scene.cameras.begin(), scene.cameras.end(), [](const io::Camera& a, const io::Camera& b) { return a.name < b.name; });
  std::vector<StrayCamera> strays = stray_cameras(scene.cameras, layout);
  if (from_video) {
    for (const StrayCamera& jump : path_jumps(scene.cameras))
      if (std::none_of(strays.begin(), strays.end(), [&](const StrayCamera& s) { return s.index == jump.index; })) strays.push_back(jump);
    std::sort(strays.begin(), strays.end(), [](const StrayCamera& a, const StrayCamera& b) { return a.index < b.index; });
  }
  // Poses left out (indices in ascending order, erased from the last so the others hold), with
  // their masks once there are masks; the layout is then found again without them.
  std::vector<std::vector<std::uint8_t>> made;
  report["stray_cameras"] = json::array();
  const auto leave_out = [&](const std::vector<StrayCamera>& wrong) {
    for (auto stray = wrong.rbegin(); stray != wrong.rend(); ++stray) {
      const std::string name = scene.cameras[stray->index].image.filename().string();
      report["stray_cameras"].push_back({{"photo", name}, {"reason", stray->reason}});
      log::warn("prepare: COLMAP's pose for ", name, " is left out: ", stray->reason);
      scene.cameras.erase(scene.cameras.begin() + std::ptrdiff_t(stray->index));
      if (!made.empty()) made.erase(made.begin() + std::ptrdiff_t(stray->index));
    }
    if (wrong.empty()) return;
    if (scene.cameras.size() < kMinPhotos)
      throw InputError("prepare: only " + std::to_string(scene.cameras.size()) + " of the photos COLMAP placed are plausible (see prepare's warnings); take more photos, in a circle around the animal");
    layout = find_layout(scene.cameras, sparse);
  };
  leave_out(strays);
  // Then those whose masks refute them (silhouette_check.hpp).
  if (automatic) {
    AutoMaskOptions mask_options;
    mask_options.working_side = working_side;
    AutoMasks found = automatic_masks(scene, sparse, layout, mask_options);
    made = std::move(found.masks);
    report["automatic_masks"] = std::move(found.report);
    leave_out(found.misplaced);
    steps.add("automatic_masks", report["automatic_masks"]["seconds"].get<double>());
    start = std::chrono::steady_clock::now();
  } else {
    // Resampled masks are soft at the outline: the same 0.5 threshold as every mask nf_gpu reads.
    for (const io::Camera& c : scene.cameras) made.push_back(io::mask_of(io::read_image(undistorted_masks / "images" / c.image.filename())));
    // The user's masks are the animal: a pose whose mask the views' silhouettes do not meet where
    // it says is COLMAP's error, and the view is left out like a stray.
    // So is a pose whose floor round the animal is not the floor the other photos show
    // (floor_consistency.hpp), which a turn round the animal can pass the silhouettes with.
    const auto check_start = std::chrono::steady_clock::now();
    std::vector<FloorAgreement> floor;
    std::vector<char> floor_refuted(scene.cameras.size(), 0);
    std::vector<StrayCamera> refuted;
    if (layout.has_floor) {
      std::vector<io::Camera> reduced;  // the photos' reduced copies, as the automatic masks judge the floor
      for (const io::Camera& c : scene.cameras) reduced.push_back(io::reduced_to(c, working_side));
      const std::vector<cv::Mat> grey = grey_photos(reduced);
      const auto find_all = [&] { return floor_agreement(reduced, grey, layout, &floor_refuted); };
      const auto with_slack = [&](std::size_t i) { return view_floor_agreement(reduced, grey, layout, i, &floor_refuted, kFloorSlackDeg); };
      for (const FloorRefutation& r : refute_poses_by_floor(floor, floor_refuted, find_all, with_slack)) refuted.push_back({r.view, r.reason});
    } else {
      floor.resize(scene.cameras.size());
    }
    const double median_floor = median_floor_agreement(floor);
    json floor_report = json::object();
    for (std::size_t i = 0; i < scene.cameras.size(); ++i) floor_report[scene.cameras[i].name] = {{"agreement", floor[i].share()}, {"pixels_judged", floor[i].judged()}};
    report["floor"] = {{"median_agreement", median_floor}, {"views", floor_report}};
    const SilhouetteCheck check = check_silhouettes(scene.cameras, made, animal_box(layout), {}, &floor_refuted);
    report["silhouettes"] = check.report(scene.cameras);
    for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
      if (check.views[i].disagrees)
        log::warn("prepare: the mask of ", scene.cameras[i].image.filename().string(), " disagrees with the silhouette the views carve together (IoU ",
                  check.views[i].iou, " against the views' median ", check.median_iou, "); check it in previews/");
      if (check.views[i].misplaced) refuted.push_back({i, check.reason(i)});
    }
    std::sort(refuted.begin(), refuted.end(), [](const StrayCamera& a, const StrayCamera& b) { return a.index < b.index; });
    leave_out(refuted);
    steps.add("pose_checks", since(check_start));
    start = std::chrono::steady_clock::now();
  }
  fs::create_directories(work / "images");
  fs::create_directories(work / "masks");
  std::vector<std::string> placed;
  fs::create_directories(work / "previews");
  for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
    io::Camera& c = scene.cameras[i];
    const std::string name = c.image.filename().string();
    placed.push_back(name);
    const fs::path image = work / "images" / name;
    fs::rename(c.image, image);
    c.image = image;
    const std::vector<std::uint8_t> inside = std::move(made[i]);
    c.mask = work / "masks" / (fs::path(name).stem().string() + ".png");
    io::write_png(c.mask, io::Image{c.width, c.height, 1, std::vector<float>(inside.begin(), inside.end())});
    write_outline_preview(work / "previews" / (fs::path(name).stem().string() + ".jpg"), c, inside);
  }
  std::vector<std::string> unplaced;
  for (const fs::path& p : photos)
    if (std::find(placed.begin(), placed.end(), p.filename().string()) == placed.end()) unplaced.push_back(p.filename().string());
  report["placed"] = placed.size();
  report["not_placed"] = unplaced;
  if (placed.size() < kMinPhotos)
    throw InputError("prepare: COLMAP placed only " + std::to_string(placed.size()) + " of " + std::to_string(photos.size()) + " photos (see " + log_file.string() + "); take more photos with more overlap");
  if (!unplaced.empty()) log::warn("prepare: COLMAP could not place ", unplaced.size(), " of ", photos.size(), " photos, left out: ", unplaced.front(), unplaced.size() > 1 ? ", ..." : "", " (all in prepare.json)");
  const auto [reprojection, points] = point_statistics(undistorted);
  report["reprojection_error_px"] = reprojection;
  report["points"] = points;
  // Upright: COLMAP's frame is the first photo's, tilted as it was held; the stages and the user's
  // 3D tools read +y as up and expect the animal near the origin.
  const glm::dmat4 to_scene = upright_transform(layout);
  for (io::Camera& c : scene.cameras) c.camera_to_world = to_scene * c.camera_to_world;
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({to_scene[0][r], to_scene[1][r], to_scene[2][r], to_scene[3][r]});
  report["frame"] = {{"up_from", layout.has_floor ? "floor" : "cameras"}, {"floor_points", layout.floor_points},
                     {"floor_tilt_deg", layout.floor_tilt_deg}, {"colmap_to_scene", rows}};
  if (layout.has_floor && layout.floor_tilt_deg > 25)
    log::warn("prepare: the floor the sparse points show tilts ", std::lround(layout.floor_tilt_deg), " degrees from the cameras' mean up; "
              "its normal is taken as up (photos held sideways, or a slope)");
  if (!layout.has_floor) log::warn("prepare: no floor among the sparse points; up is the cameras' mean up vector");
  scene.root = work;
  if (o.cm_per_unit) scene.cm_per_unit = *o.cm_per_unit;
  if (known) {
    report["known_distance"] = scale_from_known_distance(*known, lenses, scene.cameras, "--known-distance " + o.known_distance.string());
    scene.cm_per_unit = report["known_distance"]["cm_per_unit"].get<double>();
  }
  report["cm_per_unit"] = scene.cm_per_unit ? json(*scene.cm_per_unit) : json(nullptr);
  report["unit_from"] = o.cm_per_unit ? "--scene-scale" : known ? "--known-distance" : "the knowledge stage's estimate (eyes, body length)";
  if (!scene.cm_per_unit)
    log::info("prepare: COLMAP's unit is arbitrary and none was given; reconstruct will estimate it from the animal (pass --scene-scale or "
              "--known-distance for an exact one)");
  write_transforms_json(work / "transforms.json", scene);
  for (const fs::path& scratch : {undistorted, undistorted_masks, mask_input}) fs::remove_all(scratch);
  steps.add("scene", since(start));
  write_file_atomic(work / "prepare.json", report.dump(2) + "\n");
  fs::rename(work, out);
  return report;
}

}  // namespace nf::prepare
