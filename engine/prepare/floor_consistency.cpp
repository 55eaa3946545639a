#include "engine/prepare/floor_consistency.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "engine/core/parallel.hpp"
#include "engine/core/stats.hpp"
#include "engine/prepare/photo_mats.hpp"

namespace nf::prepare {

namespace {

constexpr int kHalf = 3;                 // 7 x 7 patches
constexpr int kPatch = (2 * kHalf + 1) * (2 * kHalf + 1);
constexpr std::size_t kCompared = 8;     // the views nearest in direction a pixel is compared with
constexpr double kAgree = 0.8, kDisagree = 0.3;
constexpr float kMinContrast = 4.f;      // grey levels: flatter patches say nothing

std::optional<glm::dvec3> on_floor(const io::Camera& c, glm::dvec2 pixel, const FloorPlane& floor) {
  const glm::dvec3 o = c.centre(), d = c.unproject(pixel, 1.0) - o;
  const double along = glm::dot(d, floor.normal);
  if (along >= 0) return std::nullopt;  // the ray rises: it never meets the floor
  return o + (-floor.height(o) / along) * d;
}

float bilinear(const cv::Mat& image, double x, double y) {
  // Pixel (i, j) is centred at (i + 0.5, j + 0.5).
  x -= 0.5, y -= 0.5;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const float fx = float(x - x0), fy = float(y - y0);
  const float* r0 = image.ptr<float>(y0);
  const float* r1 = image.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// Normalised cross-correlation of two patches; nullopt when either is flat.
std::optional<double> ncc(const float* a, const float* b) {
  double ma = 0, mb = 0;
  for (int k = 0; k < kPatch; ++k) ma += a[k], mb += b[k];
  ma /= kPatch, mb /= kPatch;
  double ab = 0, aa = 0, bb = 0;
  for (int k = 0; k < kPatch; ++k) ab += (a[k] - ma) * (b[k] - mb), aa += (a[k] - ma) * (a[k] - ma), bb += (b[k] - mb) * (b[k] - mb);
  if (aa < kMinContrast * kMinContrast * kPatch || bb < kMinContrast * kMinContrast * kPatch) return std::nullopt;
  return ab / std::sqrt(aa * bb);
}

}  // namespace

cv::Mat floor_evidence(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, std::size_t view,
                       const FloorPlane& floor, glm::dvec3 centre, double reach, cv::Rect region, int stride) {
  stride = std::max(1, stride);
  const io::Camera& c = cameras[view];
  cv::Mat evidence = cv::Mat::zeros(grey[view].size(), CV_8U);
  region &= cv::Rect(kHalf, kHalf, grey[view].cols - 2 * kHalf, grey[view].rows - 2 * kHalf);
  // The views looking most nearly the same way see the floor least foreshortened against this one.
  const glm::dvec3 look = glm::normalize(centre - c.centre());
  std::vector<std::pair<double, std::size_t>> by_angle;
  for (std::size_t j = 0; j < cameras.size(); ++j)
    if (j != view) by_angle.emplace_back(-glm::dot(look, glm::normalize(centre - cameras[j].centre())), j);
  std::sort(by_angle.begin(), by_angle.end());
  by_angle.resize(std::min(by_angle.size(), kCompared));
  std::vector<glm::dmat4> to_camera;
  for (const auto& [unused, j] : by_angle) to_camera.push_back(cameras[j].world_to_camera());

  float mine[kPatch], theirs[kPatch];
  for (int y = region.y; y < region.y + region.height; y += stride)
    for (int x = region.x; x < region.x + region.width; x += stride) {
      const glm::dvec2 pixel(x + 0.5, y + 0.5);
      const auto x0 = on_floor(c, pixel, floor), xu = on_floor(c, pixel + glm::dvec2(1, 0), floor), xv = on_floor(c, pixel + glm::dvec2(0, 1), floor);
      if (!x0 || !xu || !xv || glm::distance(*x0, centre) > reach) continue;
      for (int k = 0, dy = -kHalf; dy <= kHalf; ++dy)
        for (int dx = -kHalf; dx <= kHalf; ++dx) mine[k++] = grey[view].at<float>(y + dy, x + dx);
      int agree = 0, seen = 0, unsure = 0;
      for (std::size_t n = 0; n < by_angle.size(); ++n) {
        const std::size_t j = by_angle[n].second;
        const io::Camera& other = cameras[j];
        const glm::dvec3 q0 = other.project(*x0, to_camera[n]), qu = other.project(*xu, to_camera[n]), qv = other.project(*xv, to_camera[n]);
        if (q0.z <= 0) continue;
        // The patch carried through the floor: the local affine map of the plane-induced homography.
        const glm::dvec2 du = glm::dvec2(qu) - glm::dvec2(q0), dv = glm::dvec2(qv) - glm::dvec2(q0);
        const double spread = kHalf * (std::abs(du.x) + std::abs(dv.x) + std::abs(du.y) + std::abs(dv.y)) + 2;
        if (q0.x < spread || q0.y < spread || q0.x > grey[j].cols - spread || q0.y > grey[j].rows - spread) continue;
        for (int k = 0, dy = -kHalf; dy <= kHalf; ++dy)
          for (int dx = -kHalf; dx <= kHalf; ++dx) {
            const glm::dvec2 at = glm::dvec2(q0) + double(dx) * du + double(dy) * dv;
            theirs[k++] = bilinear(grey[j], at.x, at.y);
          }
        const auto score = ncc(mine, theirs);
        if (!score) continue;
        ++seen;
        agree += *score > kAgree;
        unsure += *score >= kDisagree;
      }
      if (agree >= 3) evidence.at<std::uint8_t>(y, x) = kFloor;
      else if (unsure == 0 && seen >= 3) evidence.at<std::uint8_t>(y, x) = kOffFloor;
    }
  return evidence;
}

cv::Rect floor_region(const io::Camera& camera, const AnimalBox& box) {
  const cv::Rect photo(0, 0, int(camera.width), int(camera.height));
  const glm::dmat4 to_camera = camera.world_to_camera();
  std::vector<cv::Point> drawn;
  for (const glm::dvec3& p : box.corners())
    if (const glm::dvec3 q = camera.project(p, to_camera); q.z > 0) drawn.emplace_back(int(std::lround(q.x)), int(std::lround(q.y)));
  return drawn.size() == 8 ? cv::boundingRect(drawn) & photo : photo;
}

std::vector<FloorAgreement> floor_agreement(const std::vector<io::Camera>& cameras, const SceneLayout& layout) {
  std::vector<FloorAgreement> out(cameras.size());
  if (!layout.has_floor) return out;
  const AnimalBox box = animal_box(layout);
  std::vector<cv::Mat> grey(cameras.size());
  parallel_for(cameras.size(), [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) grey[i] = grey_levels(photo_bgr(cameras[i]));
  });
  parallel_for(cameras.size(), [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) {
      const io::Camera& c = cameras[i];
      // Every stride-th pixel and row: counted with its stride squared, as if each stood for its block.
      const int stride = std::max(1, int(std::max(c.width, c.height) / 320));
      const cv::Mat e = floor_evidence(cameras, grey, i, layout.floor, box.base, floor_reach(box), floor_region(c, box), stride);
      const std::size_t block = std::size_t(stride) * std::size_t(stride);
      out[i] = {block * std::size_t(cv::countNonZero(e == kFloor)), block * std::size_t(cv::countNonZero(e == kOffFloor)), std::size_t(c.width) * c.height};
    }
  });
  return out;
}

namespace {

constexpr double kMinJudged = 0.01;     // of the photo's pixels: fewer say too little
constexpr double kMinMedianShare = 0.5;  // below, the floor itself is too unlike across views to judge by
constexpr double kRefutingFraction = 1.0 / 3.0;

bool judged_enough(const FloorAgreement& v) { return v.pixels > 0 && double(v.judged()) >= kMinJudged * double(v.pixels); }

}  // namespace

double median_floor_agreement(const std::vector<FloorAgreement>& views) {
  std::vector<double> shares;
  for (const FloorAgreement& v : views)
    if (judged_enough(v)) shares.push_back(v.share());
  return shares.empty() ? 0.0 : nf::median(shares);
}

std::vector<std::size_t> floor_refuted_views(const std::vector<FloorAgreement>& views) {
  const double median = median_floor_agreement(views);
  std::vector<std::size_t> refuted;
  if (median < kMinMedianShare) return refuted;
  for (std::size_t i = 0; i < views.size(); ++i)
    if (judged_enough(views[i]) && views[i].share() < kRefutingFraction * median) refuted.push_back(i);
  return refuted;
}

std::string floor_refutation_reason(const FloorAgreement& view, double median_share) {
  std::ostringstream s;
  s.precision(1);
  s << "the floor its pose puts around the animal matches the other photos' floor at " << std::fixed << 100 * view.share() << " % of " << view.judged()
    << " pixels judged, where the views' median is " << 100 * median_share << " %: its pose is wrong";
  return s.str();
}

}  // namespace nf::prepare
