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
// A floor the photo sees this nearly edge-on is not judged: a pixel's patch there spans a long
// strip of floor, which patches through the local affine map no longer match (a low camera's floor
// beyond the animal came out "off the floor" in whole bands and seeded them as animal: the 512 px
// cat's view 016, IoU 0.87; 0.91 without them). The same bound on the views compared with changed
// nothing there.
const double kMinFloorSine = std::sin(10.0 * M_PI / 180.0);

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
                       const FloorPlane& floor, glm::dvec3 centre, double reach, cv::Rect region, int stride,
                       const std::vector<char>* left_out, glm::dvec2 shift) {
  stride = std::max(1, stride);
  const io::Camera& c = cameras[view];
  cv::Mat evidence = cv::Mat::zeros(grey[view].size(), CV_8U);
  region &= cv::Rect(kHalf, kHalf, grey[view].cols - 2 * kHalf, grey[view].rows - 2 * kHalf);
  // The views looking most nearly the same way see the floor least foreshortened against this one.
  const glm::dvec3 look = glm::normalize(centre - c.centre());
  std::vector<std::pair<double, std::size_t>> by_angle;
  for (std::size_t j = 0; j < cameras.size(); ++j)
    if (j != view && !(left_out && (*left_out)[j])) by_angle.emplace_back(-glm::dot(look, glm::normalize(centre - cameras[j].centre())), j);
  std::sort(by_angle.begin(), by_angle.end());
  by_angle.resize(std::min(by_angle.size(), kCompared));
  std::vector<glm::dmat4> to_camera;
  for (const auto& [unused, j] : by_angle) to_camera.push_back(cameras[j].world_to_camera());

  float mine[kPatch], theirs[kPatch];
  for (int y = region.y; y < region.y + region.height; y += stride)
    for (int x = region.x; x < region.x + region.width; x += stride) {
      const glm::dvec2 pixel = glm::dvec2(x + 0.5, y + 0.5) + shift;
      const auto x0 = on_floor(c, pixel, floor), xu = on_floor(c, pixel + glm::dvec2(1, 0), floor), xv = on_floor(c, pixel + glm::dvec2(0, 1), floor);
      if (!x0 || !xu || !xv || glm::distance(*x0, centre) > reach) continue;
      if (glm::dot(glm::normalize(c.centre() - *x0), floor.normal) < kMinFloorSine) continue;
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
        const std::optional<double> score = ncc(mine, theirs);
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

cv::Mat floor_evidence_round_animal(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout, std::size_t view,
                                   int stride, const std::vector<char>* left_out, glm::dvec2 shift) {
  const AnimalBox box = animal_box(layout);
  return floor_evidence(cameras, grey, view, layout.floor, box.base, floor_reach(box), floor_region(cameras[view], box), stride, left_out, shift);
}

FloorAgreement agreement_of(const cv::Mat& evidence, int stride) {
  // Every stride-th pixel and row: counted with its stride squared, as if each stood for its block.
  const std::size_t block = std::size_t(stride) * std::size_t(stride);
  return {block * std::size_t(cv::countNonZero(evidence == kFloor)), block * std::size_t(cv::countNonZero(evidence == kOffFloor)), evidence.total()};
}

FloorAgreement best_shifted_agreement(const std::function<FloorAgreement(glm::dvec2, int)>& agreement_at, double slack_px, int stride) {
  constexpr int kSteps = 4;  // each way: a 9 x 9 grid
  const double step = slack_px / kSteps;
  std::vector<glm::dvec2> shifts;
  for (int sy = -kSteps; sy <= kSteps; ++sy)
    for (int sx = -kSteps; sx <= kSteps; ++sx) shifts.push_back(step * glm::dvec2(sx, sy));
  std::vector<FloorAgreement> found(shifts.size());
  for_each_dynamic(int(shifts.size()), [&](int k) { found[std::size_t(k)] = agreement_at(shifts[std::size_t(k)], 2 * stride); });
  // A shift that judges few pixels (its rays moved off the floor's textured part) says little: the
  // best is taken among those judging at least half the shifts' median.
  std::vector<double> judged;
  for (const FloorAgreement& f : found) judged.push_back(double(f.judged()));
  const double enough = 0.5 * nf::median(judged);
  std::size_t best = shifts.size() / 2;  // no shift
  for (std::size_t k = 0; k < found.size(); ++k)
    if (double(found[k].judged()) >= enough && found[k].share() > found[best].share()) best = k;
  return agreement_at(shifts[best], stride);
}

std::vector<cv::Mat> grey_photos(const std::vector<io::Camera>& cameras) {
  std::vector<cv::Mat> grey(cameras.size());
  for_each_dynamic(int(cameras.size()), [&](int i) { grey[std::size_t(i)] = grey_levels(photo_bgr(cameras[std::size_t(i)])); });
  return grey;
}

FloorAgreement view_floor_agreement(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout, std::size_t view,
                                    const std::vector<char>* left_out, double slack_deg) {
  const io::Camera& c = cameras[view];
  if (!layout.has_floor) return {0, 0, std::size_t(c.width) * c.height};
  const auto agreement_at = [&](glm::dvec2 shift, int stride) {
    return agreement_of(floor_evidence_round_animal(cameras, grey, layout, view, stride, left_out, shift), stride);
  };
  const int stride = std::max(1, int(std::max(c.width, c.height) / 320));
  if (slack_deg <= 0) return agreement_at(glm::dvec2(0.0), stride);
  return best_shifted_agreement(agreement_at, c.fx * std::tan(slack_deg * M_PI / 180.0), stride);
}

std::vector<FloorAgreement> floor_agreement(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout,
                                            const std::vector<char>* left_out) {
  std::vector<FloorAgreement> out(cameras.size());
  for_each_dynamic(int(cameras.size()), [&](int i) {
    if (!(left_out && (*left_out)[std::size_t(i)])) out[std::size_t(i)] = view_floor_agreement(cameras, grey, layout, std::size_t(i), left_out, 0.0);
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

std::string floor_refutation_reason(const FloorAgreement& view, const FloorAgreement& with_slack, double median_share) {
  std::ostringstream s;
  s.precision(1);
  s << "the floor its pose puts around the animal matches the other photos' floor at " << std::fixed << 100 * view.share() << " % of " << view.judged()
    << " pixels judged (" << 100 * with_slack.share() << " % with a degree's slack), where the views' median is " << 100 * median_share << " %: its pose is wrong";
  return s.str();
}

std::vector<FloorRefutation> refute_poses_by_floor(std::vector<FloorAgreement>& agreement, std::vector<char>& left_out,
                                                   const std::function<std::vector<FloorAgreement>()>& find,
                                                   const std::function<FloorAgreement(std::size_t)>& with_slack) {
  std::vector<FloorRefutation> refuted;
  std::vector<FloorAgreement> refuting;  // what each refuted view agreed when it was refuted
  std::vector<char> cleared(left_out.size(), 0);  // candidates the slack brought back
  for (agreement = find();;) {
    std::vector<std::size_t> candidates;  // left-out views judge nothing
    for (std::size_t i : floor_refuted_views(agreement))
      if (!cleared[i]) candidates.push_back(i);
    std::sort(candidates.begin(), candidates.end(), [&](std::size_t a, std::size_t b) { return agreement[a].share() < agreement[b].share(); });
    const double median = median_floor_agreement(agreement);
    std::optional<std::size_t> worst;
    for (std::size_t i : candidates) {
      const FloorAgreement slack = with_slack(i);
      if (slack.judged() > 0 && slack.share() < kRefutingFraction * median) {
        worst = i;
        refuted.push_back({i, floor_refutation_reason(agreement[i], slack, median)});
        refuting.push_back(agreement[i]);
        break;
      }
      cleared[i] = 1;
    }
    if (!worst) break;
    left_out[*worst] = 1;
    agreement = find();
  }
  for (std::size_t k = 0; k < refuted.size(); ++k) agreement[refuted[k].view] = refuting[k];
  std::sort(refuted.begin(), refuted.end(), [](const FloorRefutation& a, const FloorRefutation& b) { return a.view < b.view; });
  return refuted;
}

}  // namespace nf::prepare
