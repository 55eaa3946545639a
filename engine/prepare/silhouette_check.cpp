#include "engine/prepare/silhouette_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/stats.hpp"
#include "engine/prepare/tolerant_hull.hpp"

namespace nf::prepare {

namespace {

// The masks are compared reduced to this many pixels on their longer side, where and slid alike:
// a refuted pose moves the animal by 4 % of the photo or more (6 px here), and the sums over
// every slide stay cheap.
constexpr int kSearchSide = 160;

// The caller's mask seen as an OpenCV image, not copied (a hundred photos' masks of 12 MP are a GB).
cv::Mat mask_view(const std::vector<std::uint8_t>& mask, const io::Camera& c) {
  if (mask.size() != std::size_t(c.width) * c.height)
    throw InputError("prepare: the mask of " + c.image.filename().string() + " has " + std::to_string(mask.size()) + " pixels where its photo has " +
                     std::to_string(c.width) + " x " + std::to_string(c.height));
  return cv::Mat(int(c.height), int(c.width), CV_8U, const_cast<std::uint8_t*>(mask.data()));
}

// The IoU of `mask` with `hull` where it is, its best over slides by up to `reach_share` of the
// longer side, and that slide in full-size pixels (both masks reduced to kSearchSide): the overlap
// at every slide is one correlation of the two.
struct Slide {
  double iou = 0, best_iou = 0, shift_px = 0;
};
Slide best_slide(const cv::Mat& mask, const cv::Mat& hull, double reach_share) {
  const double scale = double(kSearchSide) / double(std::max(mask.cols, mask.rows));
  const cv::Size small(std::max(1, int(std::lround(mask.cols * scale))), std::max(1, int(std::lround(mask.rows * scale))));
  cv::Mat a, b;
  cv::resize(mask != 0, a, small, 0, 0, cv::INTER_AREA);  // any non-zero value is inside
  cv::resize(hull, b, small, 0, 0, cv::INTER_AREA);
  a.convertTo(a, CV_32F, 1.0 / 255.0), b.convertTo(b, CV_32F, 1.0 / 255.0);
  cv::threshold(a, a, 0.5, 1.0, cv::THRESH_BINARY), cv::threshold(b, b, 0.5, 1.0, cv::THRESH_BINARY);
  const int reach = std::max(1, int(std::lround(reach_share * kSearchSide)));
  cv::Mat padded, overlap;
  cv::copyMakeBorder(b, padded, reach, reach, reach, reach, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::matchTemplate(padded, a, overlap, cv::TM_CCORR);
  const double area_a = cv::sum(a)[0], area_b = cv::sum(b)[0];
  const auto iou_at = [&](int x, int y) {
    const double both = overlap.at<float>(y, x), either = area_a + area_b - both;
    return either > 0 ? both / either : 0.0;
  };
  Slide s;
  s.iou = iou_at(reach, reach);
  for (int y = 0; y < overlap.rows; ++y)
    for (int x = 0; x < overlap.cols; ++x)
      if (const double value = iou_at(x, y); value > s.best_iou + 1e-9) s.best_iou = value, s.shift_px = std::hypot(x - reach, y - reach) / scale;
  return s;
}

}  // namespace

SilhouetteCheck check_silhouettes(const std::vector<io::Camera>& cameras, const std::vector<std::vector<std::uint8_t>>& masks,
                                  const AnimalBox& box, const SilhouetteOptions& o, const std::vector<char>* left_out) {
  SilhouetteCheck out;
  const std::size_t views = cameras.size();
  out.views.resize(views);
  // A refuted view's mask (empty, or its photo's animal where its wrong pose puts it) would cost the
  // hull a view of its tolerance, and would be named among the views that disagree.
  for (std::size_t i = 0; i < views; ++i) out.views[i].left_out = left_out && (*left_out)[i];
  std::vector<cv::Mat> inside(views);
  for (std::size_t i = 0; i < views; ++i) inside[i] = mask_view(masks.at(i), cameras[i]);

  // The tolerant hull (tolerant_hull.hpp), as the automatic masks carve it.
  const HullGrid grid(box, o.cells);
  const std::vector<char> kept = grid.carve(cameras, inside, left_out);
  // A solid's outline is its surface's: only voxels with an empty 6-neighbour are drawn back.
  std::vector<glm::dvec3> surface;
  const glm::uvec3 cells = grid.cells;
  for (std::size_t z = 0; z < cells.z; ++z)
    for (std::size_t y = 0; y < cells.y; ++y)
      for (std::size_t x = 0; x < cells.x; ++x) {
        const std::size_t k = grid.index(x, y, z);
        if (!kept[k]) continue;
        ++out.hull_voxels;
        const bool boundary = x == 0 || y == 0 || z == 0 || x + 1 == cells.x || y + 1 == cells.y || z + 1 == cells.z ||
                              !kept[grid.index(x - 1, y, z)] || !kept[grid.index(x + 1, y, z)] || !kept[grid.index(x, y - 1, z)] ||
                              !kept[grid.index(x, y + 1, z)] || !kept[grid.index(x, y, z - 1)] || !kept[grid.index(x, y, z + 1)];
        if (boundary) surface.push_back(grid.centre(k));
      }
  if (out.hull_voxels == 0) return out;

  for_each_dynamic(int(views), [&](int view) {
    const auto i = std::size_t(view);
    if (out.views[i].left_out) return;
    // Discs as wide as a voxel, rounded, not raised: a pixel more all round fattens thin legs
    // against the mask compared.
    const cv::Mat hull = draw_voxels(cameras[i], surface, grid.side, 0.7, DiscRadius::rounded);
    const Slide slide = best_slide(inside[i], hull, o.max_shift);
    out.views[i].iou = slide.iou, out.views[i].shifted_iou = slide.best_iou, out.views[i].shift_px = slide.shift_px;
  });
  std::vector<double> ious;
  for (const ViewSilhouette& v : out.views)
    if (!v.left_out) ious.push_back(v.iou);
  out.median_iou = nf::median(ious);
  // Well below the others' agreement (a drawn-back hull is a little fat, so views are judged
  // against their median): a wrong pose when a slide brings the mask back within the others'
  // agreement (a slide is only near a pose's error: it leaves the change of perspective), a wrong
  // mask when none does.
  const double low = out.median_iou - std::max(0.1, 0.2 * out.median_iou);
  for (std::size_t i = 0; i < views; ++i) {
    ViewSilhouette& v = out.views[i];
    if (v.left_out || v.iou >= low) continue;
    const double least_slide = o.min_shift * double(std::max(cameras[i].width, cameras[i].height));
    v.misplaced = v.shifted_iou >= low && v.shifted_iou >= v.iou + 0.15 && v.shift_px >= least_slide;
    v.disagrees = !v.misplaced;
  }
  return out;
}

std::string SilhouetteCheck::reason(std::size_t i) const {
  const ViewSilhouette& v = views.at(i);
  if (!v.misplaced) return "";
  char why[240];
  std::snprintf(why, sizeof why,
                "its mask meets the silhouette the views carve together only %.0f px away (IoU %.2f where it is, %.2f moved; the views' median %.2f): "
                "COLMAP's pose is off",
                v.shift_px, v.iou, v.shifted_iou, median_iou);
  return why;
}

json SilhouetteCheck::report(const std::vector<io::Camera>& cameras) const {
  json per_view = json::object();
  for (std::size_t i = 0; i < views.size(); ++i) {
    const ViewSilhouette& v = views[i];
    per_view[cameras.at(i).image.filename().string()] =
        v.left_out ? json{{"left_out", true}} : json{{"iou", v.iou}, {"slid_iou", v.shifted_iou}, {"slide_px", v.shift_px}};
  }
  json misplaced = json::array(), disagreeing = json::array();
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (views[i].misplaced) misplaced.push_back(cameras[i].image.filename().string());
    if (views[i].disagrees) disagreeing.push_back(cameras[i].image.filename().string());
  }
  return {{"median_iou", median_iou}, {"hull_voxels", hull_voxels}, {"misplaced", misplaced}, {"disagreeing", disagreeing}, {"views", per_view}};
}

}  // namespace nf::prepare
