#include "engine/prepare/auto_masks.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include <opencv2/imgproc.hpp>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/stats.hpp"
#include "engine/prepare/floor_consistency.hpp"
#include "engine/prepare/keypoint_cover.hpp"
#include "engine/prepare/mask_outline.hpp"
#include "engine/prepare/photo_mats.hpp"
#include "engine/prepare/silhouette_check.hpp"
#include "engine/prepare/tolerant_hull.hpp"

namespace nf::prepare {

namespace {

std::vector<cv::Point> projected(const io::Camera& camera, const std::vector<glm::dvec3>& world) {
  std::vector<cv::Point> r;
  const glm::dmat4 to_camera = camera.world_to_camera();
  for (const glm::dvec3& p : world)
    if (const glm::dvec3 q = camera.project(p, to_camera); q.z > 0) r.emplace_back(int(std::lround(q.x)), int(std::lround(q.y)));
  return r;
}

cv::Mat foreground(const cv::Mat& labels) { return (labels == cv::GC_FGD) | (labels == cv::GC_PR_FGD); }

// GrabCut on the labels, in place. It needs pixels of both kinds to model their colours: with no
// animal left to cut, the view has none.
void graph_cut(const cv::Mat& photo, cv::Mat& labels, std::uint32_t iterations, const std::string& view) {
  if (cv::countNonZero(foreground(labels)) == 0) return;
  if (cv::countNonZero(foreground(labels)) == int(labels.total())) labels.setTo(cv::Scalar(cv::GC_PR_BGD));
  try {
    // Its colour models start from k-means on OpenCV's per-thread random numbers: seeded from the
    // view, a cut is the same whichever core makes it, and in whatever order.
    std::uint64_t seed = 0x9E3779B97F4A7C15ULL;
    for (const char ch : view) seed = (seed ^ std::uint8_t(ch)) * 0x100000001B3ULL;
    cv::theRNG().state = seed | 1;
    cv::Mat bgd, fgd;
    cv::grabCut(photo, labels, cv::Rect(), bgd, fgd, int(iterations), cv::GC_INIT_WITH_MASK);
  } catch (const cv::Exception& e) {
    throw InputError("prepare: the automatic mask of view " + view + " failed (" + e.what() + "); pass --masks DIR");
  }
}

// The 26-connected clusters of the marked cells of a grid (x fastest, then y, then z) that hold the
// animal: the one holding the most of the animal's sparse points that fall in (or next to) a marked
// cell, the cells given by `animal_cells`, and any holding a fifth of them; the largest cluster when
// none falls near one.
std::vector<char> animal_components(const std::vector<char>& marked, const glm::uvec3& cells, const std::vector<std::size_t>& animal_cells) {
  std::vector<int> component(marked.size(), -1);
  std::vector<std::size_t> sizes;
  std::vector<std::size_t> stack;
  const std::size_t nx = cells.x, ny = cells.y, nz = cells.z;
  const auto each_neighbour = [&](std::size_t k, const auto& visit) {
    const std::size_t x = k % nx, y = (k / nx) % ny, z = k / (nx * ny);
    for (std::size_t cz = z ? z - 1 : 0; cz <= std::min(z + 1, nz - 1); ++cz)
      for (std::size_t cy = y ? y - 1 : 0; cy <= std::min(y + 1, ny - 1); ++cy)
        for (std::size_t cx = x ? x - 1 : 0; cx <= std::min(x + 1, nx - 1); ++cx) visit((cz * ny + cy) * nx + cx);
  };
  for (std::size_t seed = 0; seed < marked.size(); ++seed) {
    if (!marked[seed] || component[seed] >= 0) continue;
    const int label = int(sizes.size());
    std::size_t size = 0;
    component[seed] = label;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::size_t k = stack.back();
      stack.pop_back();
      ++size;
      each_neighbour(k, [&](std::size_t n) {
        if (marked[n] && component[n] < 0) component[n] = label, stack.push_back(n);
      });
    }
    sizes.push_back(size);
  }
  std::vector<char> kept(marked.size(), 0);
  if (sizes.empty()) return kept;
  // Sparse points lie on the fur's surface, at or just outside the hull: a point counts for the
  // cluster of its cell, or of a marked neighbour.
  std::vector<std::size_t> points(sizes.size(), 0);
  std::size_t placed = 0;
  for (const std::size_t cell : animal_cells) {
    int found = component[cell];
    if (found < 0) each_neighbour(cell, [&](std::size_t n) { found = found < 0 ? component[n] : found; });
    if (found >= 0) ++points[std::size_t(found)], ++placed;
  }
  // The cluster with the most points always (the largest when none holds one), and any other that
  // holds a fifth of them.
  std::vector<char> chosen(sizes.size(), 0);
  const auto& by = placed > 0 ? points : sizes;
  chosen[std::size_t(std::max_element(by.begin(), by.end()) - by.begin())] = 1;
  for (std::size_t c = 0; c < sizes.size(); ++c) chosen[c] |= placed > 0 && 5 * points[c] >= placed;
  for (std::size_t k = 0; k < marked.size(); ++k) kept[k] = component[k] >= 0 && chosen[std::size_t(component[k])];
  return kept;
}

}  // namespace

AutoMasks automatic_masks(const io::Scene& scene, const SparsePoints& points, const SceneLayout& layout, const AutoMaskOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  AutoMasks out;
  json& report = out.report;
  const glm::dvec3 focus = layout.focus;
  const double reach = layout.reach;
  const bool has_floor = layout.has_floor;
  const std::vector<char>&animal = layout.animal, &background = layout.background;
  const std::vector<glm::dvec3>& animal_points = layout.animal_points;
  report["focus"] = {focus.x, focus.y, focus.z};
  report["camera_distance"] = reach;
  report["floor_found"] = has_floor;
  report["working_side"] = o.working_side;
  report["floor_points"] = layout.floor_points;
  report["animal_points"] = animal_points.size();
  // The points bound the animal's box and seed its likely pixels; with a floor, the floor's evidence
  // (what the other views see on it) finds the rest, so fewer will do.
  const std::size_t needed = has_floor ? 10 : 20;
  if (animal_points.size() < needed)
    throw InputError("prepare: only " + std::to_string(animal_points.size()) + " sparse points stand above the floor near where the cameras aim, too few to say "
                     "where the animal is; pass --masks DIR (one mask per photo) or take the photos closer, around the animal");
  if (!has_floor) log::warn("prepare: no floor found among the sparse points; the automatic masks rely on the animal's distance from the cameras alone");

  const AnimalBox extent = animal_box(layout);
  const std::vector<glm::dvec3> corners = extent.corners();

  const std::size_t views = scene.cameras.size();
  // Everything up to the final outlines works on reduced copies of the photos (AutoMaskOptions).
  std::vector<io::Camera> cameras;
  for (const io::Camera& c : scene.cameras) cameras.push_back(io::reduced_to(c, o.working_side));
  std::vector<cv::Mat> photos(views), labels(views), cut(views);
  std::vector<char> left_out(views, 0);  // misplaced views: no part in the hull
  std::vector<cv::Mat> hull_masks(views);
  std::vector<cv::Mat> grey(views);
  std::vector<cv::Mat> floor_evidences(views);
  // One view per core at a time (parallel_for would give a few dozen views one thread).
  for_each_dynamic(int(views), [&](int i) {
    photos[std::size_t(i)] = photo_bgr(cameras[std::size_t(i)]);
    grey[std::size_t(i)] = grey_levels(photos[std::size_t(i)]);
  });
  const auto first_cut = [&](std::size_t i) {
    const io::Camera& c = cameras[i];
    const double to_working = double(c.width) / double(scene.cameras[i].width);  // keypoints are found at the photo's size
    cv::Mat& l = labels[i];
    l = cv::Mat(int(c.height), int(c.width), CV_8U, cv::Scalar(cv::GC_BGD));
    std::vector<cv::Point> box = projected(c, corners), hull;
    if (box.size() == 8) {
      cv::convexHull(box, hull);
      cv::fillConvexPoly(l, hull, cv::Scalar(cv::GC_PR_BGD));
    } else {
      l.setTo(cv::Scalar(cv::GC_PR_BGD));  // the camera is inside the box: no bound
    }
    if (std::vector<cv::Point> inside = projected(c, animal_points); inside.size() >= 3) {
      cv::convexHull(inside, hull);
      cv::fillConvexPoly(l, hull, cv::Scalar(cv::GC_PR_FGD));
    }
    if (has_floor) {
      // What the other views say of the floor inside the box: floor is background, pixels that no
      // view sees on the floor stand above it (legs and paws, whose sparse points are few).
      const cv::Mat& evidence = floor_evidences[i];
      // Off-floor pixels in a solid patch are certain; lone ones only likely.
      cv::Mat off = evidence == kOffFloor, solid;
      cv::erode(off, solid, cv::Mat());
      l.setTo(cv::Scalar(cv::GC_PR_FGD), off & (l != cv::GC_BGD));
      l.setTo(cv::Scalar(cv::GC_FGD), solid & (l != cv::GC_BGD));
      // Floor is certain away from the animal; next to it (where paws stand, their floor point
      // all but their own) it is only likely, and the colours decide.
      const int near_px = std::max(3, int(std::lround(0.02 * std::max(l.cols, l.rows))));
      cv::Mat near_animal;
      cv::dilate(off, near_animal, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * near_px + 1, 2 * near_px + 1)));
      l.setTo(cv::Scalar(cv::GC_BGD), (evidence == kFloor) & (near_animal == 0));
      l.setTo(cv::Scalar(cv::GC_PR_BGD), (evidence == kFloor) & near_animal);
    }
    const auto seen = points.observed.find(c.image.filename().string());
    if (seen != points.observed.end())
      for (const Observation& ob : seen->second) {
        const cv::Point at(int(std::lround(ob.pixel.x * to_working)), int(std::lround(ob.pixel.y * to_working)));
        if (animal[ob.point]) cv::circle(l, at, 2, cv::Scalar(cv::GC_FGD), cv::FILLED);
        else if (background[ob.point]) cv::circle(l, at, 2, cv::Scalar(cv::GC_BGD), cv::FILLED);
      }
    graph_cut(photos[i], l, o.grabcut_iterations, c.name);
    cut[i] = foreground(l);
  };

  // The visual hull of the cuts: voxels of the box that the views in whose frame they lie see inside
  // their cuts, all but a fifth (a few wrong cuts must not carve the others); drawn back into each
  // view as discs of the voxel's size.
  const HullGrid grid(extent, o.hull_cells);
  std::vector<std::size_t> animal_cells;
  for (const glm::dvec3& p : animal_points)
    if (const std::optional<std::size_t> cell = grid.cell_of(p)) animal_cells.push_back(*cell);
  const auto carve = [&] {
    // The animal is one solid: a cluster of voxels apart from the one its sparse points lie in is
    // where a few views' cuts took the same patch of wall or floor, and drawn back it would hold
    // that patch in their masks.
    const std::vector<char> animal_voxels = animal_components(grid.carve(cameras, cut, &left_out), grid.cells, animal_cells);
    std::vector<glm::dvec3> voxels;
    for (std::size_t k = 0; k < grid.total(); ++k)
      if (animal_voxels[k]) voxels.push_back(grid.centre(k));
    // Discs a little wider than a voxel, raised: the cuts grow back inside a hull that is not short of the animal.
    for_each_dynamic(int(views), [&](int i) { hull_masks[std::size_t(i)] = draw_voxels(cameras[std::size_t(i)], voxels, grid.side, 0.8, DiscRadius::rounded_up); });
    return voxels.size();
  };
  const auto hull_cut = [&](std::size_t i) {
    // Outside the (slightly grown) hull is background, well inside it and cut as animal is animal,
    // the band between is the graph cut's to decide.
    const int grow = std::max(2, int(std::lround(0.004 * std::max(photos[i].cols, photos[i].rows))));
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow + 1, 2 * grow + 1));
    cv::Mat grown, far, shrunk;
    cv::dilate(hull_masks[i], grown, kernel);
    cv::dilate(hull_masks[i], far, kernel, cv::Point(-1, -1), 4);
    cv::erode(hull_masks[i], shrunk, kernel, cv::Point(-1, -1), 2);
    cv::Mat& l = labels[i];
    // What the first cut was sure of stays; the hull moves the rest.
    l.setTo(cv::Scalar(cv::GC_PR_BGD), (l == cv::GC_PR_FGD) | (l == cv::GC_PR_BGD));
    l.setTo(cv::Scalar(cv::GC_PR_FGD), (grown & cut[i]) & (l != cv::GC_BGD) & (l != cv::GC_FGD));
    l.setTo(cv::Scalar(cv::GC_FGD), shrunk & cut[i]);
    l.setTo(cv::Scalar(cv::GC_BGD), far == 0);
    graph_cut(photos[i], l, o.grabcut_iterations, cameras[i].name);
    cut[i] = foreground(l);
  };

  // Each photo's cut is independent of the others': one per core. Views left out (a wrong pose)
  // are not cut again.
  const auto each_view = [&](const auto& body) {
    for_each_dynamic(int(views), [&](int i) {
      if (!left_out[std::size_t(i)]) body(std::size_t(i));
    });
  };
  // A pose COLMAP got wrong, seen in the floor's evidence: the floor it puts round the animal is
  // not the floor the other photos show (floor_consistency.hpp). Such a view is left out, and the
  // others' evidence found again without it, which the first cuts then use: compared with it,
  // their floor agreed less (a turned view's neighbour fell from 0.9 to 0.37, its mask to 0.87).
  std::vector<FloorAgreement> floor_agreement(views);
  const auto find_floor = [&](std::size_t i) {
    floor_evidences[i] = floor_evidence_round_animal(cameras, grey, layout, i, 1, &left_out);
    floor_agreement[i] = agreement_of(floor_evidences[i]);
  };
  if (has_floor) {
    const auto find_all = [&] {
      std::fill(floor_agreement.begin(), floor_agreement.end(), FloorAgreement{});
      each_view(find_floor);
      return floor_agreement;
    };
    const auto with_slack = [&](std::size_t i) { return view_floor_agreement(cameras, grey, layout, i, &left_out, kFloorSlackDeg); };
    for (const FloorRefutation& r : refute_poses_by_floor(floor_agreement, left_out, find_all, with_slack)) out.misplaced.push_back({r.view, r.reason});
  }
  report["median_floor_agreement"] = median_floor_agreement(floor_agreement);
  each_view(first_cut);
  for (std::size_t i = 0; i < views; ++i)  // a view left out here is cut nowhere: an empty mask
    if (left_out[i]) cut[i] = cv::Mat::zeros(int(cameras[i].height), int(cameras[i].width), CV_8U);
  // Or the photo's own cut (its seeds are its keypoints, where the animal really is) meets the
  // silhouette the views carve together only when moved.
  {
    std::vector<std::vector<std::uint8_t>> first(views);
    for (std::size_t i = 0; i < views; ++i) first[i].assign(cut[i].datastart, cut[i].dataend);
    SilhouetteCheck check = check_silhouettes(cameras, first, extent, {}, &left_out);
    for (std::size_t i = 0; i < views; ++i)  // the slides in the photos' own pixels, as the report and the reasons say
      check.views[i].shift_px *= double(scene.cameras[i].width) / double(cameras[i].width);
    report["first_cuts"] = check.report(scene.cameras);
    for (std::size_t i = 0; i < views; ++i)
      if (check.views[i].misplaced && !left_out[i]) left_out[i] = 1, out.misplaced.push_back({i, check.reason(i)});
  }
  std::size_t voxels = 0;
  for (std::uint32_t round = 1; round < o.rounds; ++round) {
    voxels = carve();
    if (voxels == 0) throw InputError("prepare: the automatic masks share no volume across the views (the cameras or the photos disagree); pass --masks DIR");
    each_view(hull_cut);
  }
  voxels = carve();
  // The hull drawn back is a little fat (discs, voxels), so a view is judged against the others:
  // its agreement with the hull against the views' median.
  const auto hull_agreement = [&](std::size_t i) { return mask_iou(cut[i], hull_masks[i]); };
  std::vector<double> shares(views), agreement(views), kept_shares, kept_agreement;
  for (std::size_t i = 0; i < views; ++i) {
    shares[i] = double(cv::countNonZero(cut[i])) / double(cut[i].total()), agreement[i] = hull_agreement(i);
    if (!left_out[i]) kept_shares.push_back(shares[i]), kept_agreement.push_back(agreement[i]);
  }
  const double median_share = nf::median(kept_shares), median_agreement = nf::median(kept_agreement);
  if (median_share == 0)  // nothing below would notice: every view agrees with an empty hull
    throw InputError("prepare: the automatic masks found no animal in most views; pass --masks DIR (one mask per photo)");
  // A cut that lost the animal, or caught something else (a view whose seeds and colours misled the
  // graph cut: its agreement with the hull the other views share far below theirs), is cut again
  // from that hull alone; if that cut fails too, the hull itself is taken. Either way it is named.
  std::vector<std::string> recut, replaced;
  for (std::size_t i = 0; i < views; ++i) {
    if (left_out[i] || cv::countNonZero(hull_masks[i]) == 0 || (shares[i] >= 0.3 * median_share && agreement[i] >= 0.5 * median_agreement)) continue;
    labels[i].setTo(cv::Scalar(cv::GC_PR_BGD));
    cut[i] = hull_masks[i].clone();
    hull_cut(i);
    if (hull_agreement(i) < 0.5 * median_agreement || cv::countNonZero(cut[i]) == 0) {
      cut[i] = hull_masks[i].clone();
      replaced.push_back(scene.cameras[i].name);
    } else {
      recut.push_back(scene.cameras[i].name);
    }
    agreement[i] = hull_agreement(i);
  }
  report["recut_from_hull"] = recut;
  report["replaced_by_hull"] = replaced;
  // The cuts drawn back at the photos' own size, their outlines moved onto the photos' edges there
  // (mask_outline.hpp): GrabCut's smoothness term leaves them a pixel or two off, on either side,
  // and a reduced cut a pixel of its own size.
  std::vector<int> outline_moved(views, 0);
  std::vector<std::vector<std::uint8_t>> masks(views);
  each_view([&](std::size_t i) {
    const io::Camera& c = scene.cameras[i];
    const cv::Mat photo = cameras[i].width == c.width ? photos[i] : photo_bgr(c);
    cv::Mat drawn = cut[i];
    if (drawn.size() != photo.size()) {
      cv::resize(cut[i], drawn, photo.size(), 0, 0, cv::INTER_LINEAR);  // a smooth outline, not the reduced pixels' steps
      drawn = drawn >= 128;
    }
    const cv::Mat snapped = snap_outline_to_photo(photo, drawn);
    outline_moved[i] = cv::countNonZero(snapped != drawn);
    masks[i].assign(snapped.datastart, snapped.dataend);
    for (std::uint8_t& m : masks[i]) m = m ? 1 : 0;
  });
  for (std::size_t i = 0; i < views; ++i)  // a view left out has an empty mask
    if (left_out[i]) masks[i].assign(std::size_t(scene.cameras[i].width) * scene.cameras[i].height, 0);
  // The photo's own keypoints on the animal against its mask (keypoint_cover.hpp): a view whose
  // mask leaves most of them out has a pose that puts the animal elsewhere, and is left out.
  const std::vector<KeypointCover> covers = animal_keypoint_cover(scene.cameras, points, animal, background, masks);
  for (std::size_t i = 0; i < views; ++i)
    if (!left_out[i] && covers[i].refutes()) {
      left_out[i] = 1;
      out.misplaced.push_back({i, covers[i].reason()});
    }
  // In ascending order, which the caller relies on to erase them from the last.
  std::sort(out.misplaced.begin(), out.misplaced.end(), [](const StrayCamera& a, const StrayCamera& b) { return a.index < b.index; });
  if (!recut.empty() || !replaced.empty())
    log::warn("prepare: ", recut.size() + replaced.size(), " automatic mask(s) lost the animal or caught something else, and were made again from the other views' hull: ",
              recut.empty() ? replaced.front() : recut.front(), recut.size() + replaced.size() > 1 ? ", ..." : "");
  report["hull_voxels"] = voxels;
  report["hull_voxel_size"] = grid.side;
  report["median_hull_iou"] = median_agreement;
  json per_view = json::array();
  std::vector<std::string> flagged;
  for (std::size_t i = 0; i < views; ++i) {
    const io::Camera& c = scene.cameras[i];
    per_view.push_back({{"view", c.name}, {"animal_share", double(std::count(masks[i].begin(), masks[i].end(), 1)) / double(masks[i].size())}, {"hull_iou", agreement[i]},
                        {"outline_moved_pixels", outline_moved[i]}, {"floor_pixels", floor_agreement[i].floor}, {"off_floor_pixels", floor_agreement[i].off_floor}, {"floor_agreement", floor_agreement[i].share()},
                        {"animal_keypoints", covers[i].seen}, {"animal_keypoints_inside", covers[i].inside},
                        {"background_keypoints_inside", covers[i].background_inside}, {"background_keypoints_expected", covers[i].background_expected},
                        {"left_out", left_out[i] != 0}});
    if (!left_out[i] && agreement[i] < median_agreement - 0.08) flagged.push_back(c.name);  // well below the views' median
  }
  out.masks = std::move(masks);
  report["views"] = per_view;
  report["disagreeing_views"] = flagged;
  if (!flagged.empty()) log::warn("prepare: ", flagged.size(), " automatic mask(s) disagree with the other views' hull (IoU with it 0.08 below the views' median): ", flagged.front(), flagged.size() > 1 ? ", ..." : "", "; check them in previews/");
  report["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace nf::prepare
