#include "engine/body/photo_eyes.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "engine/core/log.hpp"
#include "engine/io/image.hpp"

namespace nf::body {
namespace {

// Sums over axis-aligned boxes of a window of the image (and of its mask), in O(1) per box.
class BoxSums {
 public:
  BoxSums(const FaceImage& image, int x0, int y0, int x1, int y1) : x0_(x0), y0_(y0), w_(x1 - x0 + 1), h_(y1 - y0 + 1) {
    value_.assign(std::size_t(w_ + 1) * std::size_t(h_ + 1), glm::dvec3(0.0));
    inside_.assign(value_.size(), 0.0);
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const int ix = x0 + x, iy = y0 + y;
        const bool in_image = ix >= 0 && iy >= 0 && ix < int(image.width) && iy < int(image.height);
        const std::size_t p = std::size_t(iy) * image.width + std::size_t(ix);
        const double counts = in_image && (image.mask.empty() || image.mask[p]) ? 1.0 : 0.0;
        const glm::dvec3 v = counts > 0 ? glm::dvec3(image.rgb[p]) : glm::dvec3(0.0);
        value_[at(x + 1, y + 1)] = v + value_[at(x, y + 1)] + value_[at(x + 1, y)] - value_[at(x, y)];
        inside_[at(x + 1, y + 1)] = counts + inside_[at(x, y + 1)] + inside_[at(x + 1, y)] - inside_[at(x, y)];
      }
  }
  // Sum and count of the counted pixels in [x - r, x + r] x [y - r, y + r] (image coordinates).
  std::pair<glm::dvec3, double> box(int x, int y, int r) const {
    const int ax = std::clamp(x - r - x0_, 0, w_), bx = std::clamp(x + r + 1 - x0_, 0, w_);
    const int ay = std::clamp(y - r - y0_, 0, h_), by = std::clamp(y + r + 1 - y0_, 0, h_);
    const auto sum = [&](const auto& t) { return t[at(bx, by)] - t[at(ax, by)] - t[at(bx, ay)] + t[at(ax, ay)]; };
    return {sum(value_), sum(inside_)};
  }

 private:
  std::size_t at(int x, int y) const { return std::size_t(y) * std::size_t(w_ + 1) + std::size_t(x); }
  int x0_, y0_, w_, h_;
  std::vector<glm::dvec3> value_;
  std::vector<double> inside_;
};

glm::dvec3 ray_direction(const io::Camera& c, glm::dvec2 pixel) { return glm::normalize(c.unproject(pixel, 1.0) - c.centre()); }

FaceImage face_image_of(const io::Camera& camera) {
  const io::Image photo = io::read_image(camera.image);
  FaceImage g;
  g.width = photo.width, g.height = photo.height;
  g.rgb.resize(std::size_t(photo.width) * photo.height);
  for (std::size_t p = 0; p < g.rgb.size(); ++p) {
    const float* px = &photo.pixels[p * photo.channels];
    g.rgb[p] = photo.channels >= 3 ? glm::vec3(px[0], px[1], px[2]) : glm::vec3(px[0]);
  }
  if (!camera.mask.empty()) g.mask = io::mask_of(io::read_image(camera.mask));
  else if (photo.channels == 2 || photo.channels == 4) g.mask = io::mask_of(photo);
  if (g.mask.size() != g.rgb.size()) g.mask.clear();
  return g;
}

}  // namespace

// How far the blob's centre may follow its centroid: each step moves it at most the window's reach.
constexpr int kMeanShiftSteps = 8;

std::vector<BlobHit> find_eye_blobs(const FaceImage& image, glm::dvec2 centre, double search_radius, double radius,
                                    double min_contrast, std::size_t max_count) {
  const int r = std::max(1, int(std::lround(radius))), ring = 2 * r;
  const int reach = int(std::ceil(search_radius));
  // The contrast is kept r beyond the search disc: a blob's curvature is measured r either side of it.
  const int extent = reach + r, span = 2 * extent + 1;
  // Pixel (i, j) has its centre at (i + 0.5, j + 0.5).
  const int cx = int(std::floor(centre.x)), cy = int(std::floor(centre.y));
  const BoxSums sums(image, cx - extent - ring - 1, cy - extent - ring - 1, cx + extent + ring + 1, cy + extent + ring + 1);
  const auto index = [&](int dx, int dy) { return std::size_t(dy + extent) * std::size_t(span) + std::size_t(dx + extent); };
  std::vector<double> contrast(std::size_t(span) * std::size_t(span), 0.0);  // 0 where the ring leaves the animal
  const double full_ring = double((2 * ring + 1) * (2 * ring + 1));
  std::vector<glm::ivec2> scored;
  for (int dy = -extent; dy <= extent; ++dy)
    for (int dx = -extent; dx <= extent; ++dx) {
      const auto [in_sum, in_count] = sums.box(cx + dx, cy + dy, r);
      const auto [out_sum, out_count] = sums.box(cx + dx, cy + dy, ring);
      if (out_count < 0.9 * full_ring || out_count - in_count <= 0) continue;  // off the animal or the photo
      const double c = glm::length((out_sum - in_sum) / (out_count - in_count) - in_sum / in_count);
      contrast[index(dx, dy)] = c;
      if (c >= min_contrast && dx * dx + dy * dy <= reach * reach) scored.push_back({dx, dy});
    }
  // Peaks: no neighbour higher (of equal ones, the first in scan order).
  struct Peak {
    glm::ivec2 at;
    double contrast, roundness;
  };
  std::vector<Peak> peaks;
  for (const glm::ivec2 d : scored) {
    const double c = contrast[index(d.x, d.y)];
    bool peak = true;
    for (int oy = -1; oy <= 1; ++oy)
      for (int ox = -1; ox <= 1; ++ox) {
        const double n = contrast[index(d.x + ox, d.y + oy)];
        const bool earlier = oy < 0 || (oy == 0 && ox < 0);
        peak = peak && (n < c || (n == c && !earlier) || (ox == 0 && oy == 0));
      }
    if (!peak) continue;
    // Roundness: how the contrast falls away from the peak in its flattest direction against its
    // steepest (the Hessian's eigenvalues r pixels out). An eye falls away all round (1); a stripe
    // or a patch's edge runs on along itself (0).
    const auto at = [&](int ox, int oy) { return contrast[index(d.x + ox, d.y + oy)]; };
    const double c0 = at(0, 0), hxx = at(r, 0) + at(-r, 0) - 2 * c0, hyy = at(0, r) + at(0, -r) - 2 * c0;
    const double hxy = 0.25 * (at(r, r) - at(r, -r) - at(-r, r) + at(-r, -r));
    const double mean = 0.5 * (hxx + hyy), half_gap = std::sqrt(0.25 * (hxx - hyy) * (hxx - hyy) + hxy * hxy);
    const double steep = mean - half_gap, flat = mean + half_gap;  // both negative at a round peak
    peaks.push_back({d, c0, steep < 0 && flat < 0 ? flat / steep : 0.0});
  }
  // The eye is the round blob that stands out: contrast times roundness ranks them.
  std::stable_sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return a.contrast * a.roundness > b.contrast * b.roundness; });
  if (peaks.size() > max_count) peaks.resize(max_count);
  std::vector<BlobHit> hits;
  for (const Peak& peak : peaks) {
    const int bx = cx + peak.at.x, by = cy + peak.at.y;
    const double peak_contrast = peak.contrast;
    // Sub-pixel: the centroid of the blob's area near the peak. A pixel counts by how far it differs
    // from the ring's mean colour towards the blob's (a stripe of another colour beside it does not
    // pull): nothing below a quarter of the blob's contrast (fur texture), fully from three quarters
    // (a pixel at the edge by the share it covers). Not by how much more it differs: an eyeball lit
    // from above is darker below, which pulled the centre down (on the body bench the eyes' median
    // error went from 6.8 to 5.7 mm).
    const auto [ring_sum, ring_count] = sums.box(bx, by, ring);
    const auto [core_sum, core_count] = sums.box(bx, by, r);
    const glm::dvec3 ring_mean = (ring_sum - core_sum) / (ring_count - core_count);
    const glm::dvec3 towards_blob = (core_sum / core_count - ring_mean) / peak_contrast;
    const double reach_px = 1.5 * radius + 0.5;
    const auto centroid_near = [&](glm::dvec2 c) -> std::optional<glm::dvec2> {
      glm::dvec2 weighted(0.0);
      double total = 0;
      const int x0 = int(std::floor(c.x - reach_px)), x1 = int(std::ceil(c.x + reach_px));
      const int y0 = int(std::floor(c.y - reach_px)), y1 = int(std::ceil(c.y + reach_px));
      for (int y = std::max(0, y0); y <= std::min(int(image.height) - 1, y1); ++y)
        for (int x = std::max(0, x0); x <= std::min(int(image.width) - 1, x1); ++x) {
          const std::size_t p = std::size_t(y) * image.width + std::size_t(x);
          if (!image.mask.empty() && !image.mask[p]) continue;
          const glm::dvec2 at(x + 0.5, y + 0.5);
          if (glm::distance(at, c) > reach_px) continue;
          const double towards = glm::dot(glm::dvec3(image.rgb[p]) - ring_mean, towards_blob);
          const double w = std::clamp((towards - 0.25 * peak_contrast) / (0.5 * peak_contrast), 0.0, 1.0);
          weighted += w * at, total += w;
        }
      if (total <= 0) return std::nullopt;
      return weighted / total;
    };
    // Mean shift: the window follows its centroid. The filter's peak can sit off the eye's centre
    // (fur across the eye, an eye wider than the template's), and one centroid round the peak stays
    // on its side: following it took the body bench's per-eye error's median from 6.2 to 5.2 mm.
    glm::dvec2 centre_px(bx + 0.5, by + 0.5);
    for (int iteration = 0; iteration < kMeanShiftSteps; ++iteration) {
      const std::optional<glm::dvec2> next = centroid_near(centre_px);
      if (!next) break;
      const double moved = glm::distance(*next, centre_px);
      centre_px = *next;
      if (moved < 0.01) break;
    }
    hits.push_back({centre_px, peak_contrast, peak.roundness});
  }
  return hits;
}

std::optional<BlobHit> find_eye_blob(const FaceImage& image, glm::dvec2 centre, double search_radius, double radius,
                                      double min_contrast) {
  const std::vector<BlobHit> hits = find_eye_blobs(image, centre, search_radius, radius, min_contrast, 1);
  if (hits.empty()) return std::nullopt;
  return hits.front();
}

namespace {

// The point closest to the observations' rays (least squares); none when the rays are parallel.
std::optional<glm::dvec3> closest_point(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations) {
  glm::dmat3 a(0.0);
  glm::dvec3 b(0.0);
  for (const EyeObservation& o : observations) {
    const io::Camera& c = cameras[o.view];
    const glm::dvec3 d = ray_direction(c, o.pixel);
    const glm::dmat3 p = glm::dmat3(1.0) - glm::outerProduct(d, d);
    a += p, b += p * c.centre();
  }
  if (std::fabs(glm::determinant(a)) < 1e-12) return std::nullopt;
  return glm::inverse(a) * b;
}

double reprojection_error(const io::Camera& camera, const EyeObservation& o, const glm::dvec3& x) {
  const glm::dvec3 p = camera.project(x);
  return p.z > 0 ? glm::distance(glm::dvec2(p), o.pixel) : 1e30;
}

double widest_angle_deg(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations, const glm::dvec3& x) {
  double widest = 0;
  for (std::size_t i = 0; i < observations.size(); ++i)
    for (std::size_t j = i + 1; j < observations.size(); ++j) {
      const glm::dvec3 u = glm::normalize(cameras[observations[i].view].centre() - x);
      const glm::dvec3 v = glm::normalize(cameras[observations[j].view].centre() - x);
      widest = std::max(widest, std::acos(std::clamp(glm::dot(u, v), -1.0, 1.0)) * 180.0 / M_PI);
    }
  return widest;
}

// Each view's observation nearest the projection of x, where within max_error_px (a view may hold
// several candidates; it agrees through one).
std::vector<EyeObservation> agreeing(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations,
                                     const glm::dvec3& x, double max_error_px, double* error_sum) {
  std::vector<EyeObservation> agree;
  std::vector<double> errors;
  for (const EyeObservation& o : observations) {
    const double e = reprojection_error(cameras[o.view], o, x);
    if (e > max_error_px) continue;
    const auto same = std::find_if(agree.begin(), agree.end(), [&](const EyeObservation& a) { return a.view == o.view; });
    if (same == agree.end()) agree.push_back(o), errors.push_back(e);
    else if (const std::size_t k = std::size_t(same - agree.begin()); e < errors[k]) *same = o, errors[k] = e;
  }
  *error_sum = 0;
  for (const double e : errors) *error_sum += e;
  return agree;
}

}  // namespace

TriangulatedPoint triangulate(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations,
                              double max_error_px, double min_angle_deg) {
  TriangulatedPoint out;
  std::vector<std::uint32_t> seen_views;
  for (const EyeObservation& o : observations)
    if (std::find(seen_views.begin(), seen_views.end(), o.view) == seen_views.end()) seen_views.push_back(o.view);
  if (seen_views.size() < 2) {
    out.reason = "seen in " + std::to_string(seen_views.size()) + " view(s)";
    return out;
  }
  // Every pair of observations from two views far enough apart proposes a point; the one whose
  // agreeing views (within max_error_px) score most wins (then the more views, then the smaller error
  // sum), and all of them refine it.
  std::vector<EyeObservation> best;
  double best_score = 0, best_error = 0;
  for (std::size_t i = 0; i < observations.size(); ++i)
    for (std::size_t j = i + 1; j < observations.size(); ++j) {
      if (observations[i].view == observations[j].view) continue;
      const std::vector<EyeObservation> pair{observations[i], observations[j]};
      const std::optional<glm::dvec3> x = closest_point(cameras, pair);
      if (!x || widest_angle_deg(cameras, pair, *x) < min_angle_deg) continue;
      double error = 0, score = 0;
      const std::vector<EyeObservation> agree = agreeing(cameras, observations, *x, max_error_px, &error);
      for (const EyeObservation& o : agree) score += o.score;
      if (std::tuple(score, agree.size(), -error) > std::tuple(best_score, best.size(), -best_error))
        best = agree, best_score = score, best_error = error;
    }
  if (best.size() < 2) {
    out.reason = "no two views agree within " + std::to_string(max_error_px) + " px from " + std::to_string(min_angle_deg) +
                 " degrees apart or more (" + std::to_string(seen_views.size()) + " views saw a candidate)";
    return out;
  }
  std::optional<glm::dvec3> x = closest_point(cameras, best);
  // The refit may push a view past the bound; it then leaves, and the rest refit.
  while (x && best.size() > 2) {
    std::size_t worst = 0;
    double worst_error = -1;
    for (std::size_t k = 0; k < best.size(); ++k)
      if (const double e = reprojection_error(cameras[best[k].view], best[k], *x); e > worst_error) worst_error = e, worst = k;
    if (worst_error <= max_error_px) break;
    best.erase(best.begin() + std::ptrdiff_t(worst));
    x = closest_point(cameras, best);
  }
  if (!x) {
    out.reason = "the views' rays are parallel";
    return out;
  }
  // The refit must keep what the proposal promised: every kept view within the bound, and rays
  // that meet at the minimum angle.
  for (const EyeObservation& o : best)
    if (reprojection_error(cameras[o.view], o, *x) > max_error_px) {
      out.reason = "the two views left disagree by more than " + std::to_string(max_error_px) + " px";
      return out;
    }
  if (const double widest = widest_angle_deg(cameras, best, *x); widest < min_angle_deg) {
    out.reason = "the views that agree see it from within " + std::to_string(widest) + " degrees";
    return out;
  }
  double sum2 = 0;
  for (const EyeObservation& o : best) sum2 += std::pow(reprojection_error(cameras[o.view], o, *x), 2);
  out.position = x;
  out.reprojection_rms_px = std::sqrt(sum2 / double(best.size()));
  for (const EyeObservation& o : best) out.views.push_back(o.view), out.score += o.score;
  return out;
}

std::vector<TriangulatedPoint> triangulate_hypotheses(const std::vector<io::Camera>& cameras, std::vector<EyeObservation> observations,
                                                      double max_error_px, std::size_t max_count, double min_angle_deg) {
  std::vector<TriangulatedPoint> out;
  while (out.size() < max_count) {
    TriangulatedPoint t = triangulate(cameras, observations, max_error_px, min_angle_deg);
    if (!t.position) break;
    // The next hypothesis may not reuse what this one explains.
    std::erase_if(observations, [&](const EyeObservation& o) { return reprojection_error(cameras[o.view], o, *t.position) <= max_error_px; });
    out.push_back(std::move(t));
  }
  return out;
}

std::optional<double> PhotoEyes::distance() const {
  if (!left.position || !right.position) return std::nullopt;
  return glm::distance(*left.position, *right.position);
}

namespace {
// Each view offers a few blobs per eye: in one view a stripe or a patch's edge may outrank the eye,
// which the views together then outvote.
constexpr std::size_t kCandidatesPerView = 4, kHypothesesPerEye = 4;
// How far (in eye distances) one eye may lie from the other's mirror image across the fitted head.
constexpr double kMaxEyeAsymmetry = 0.35;
// The eye's opening against the eyeball's radius: the lids cover its rim, and a blob filter wider
// than the opening averages fur into it.
constexpr double kOpeningFraction = 0.75;
}  // namespace

PhotoEyes find_eyes_in_photos(const io::Scene& scene, const EyeSearch& search) {
  PhotoEyes out;
  const double eye_distance = glm::distance(search.left, search.right);
  std::vector<EyeObservation> seen[2];
  std::vector<double> radii_px;
  const glm::dvec3 fitted[2] = {search.left, search.right};
  for (std::uint32_t v = 0; v < scene.cameras.size(); ++v) {
    const io::Camera& cam = scene.cameras[v];
    if (cam.image.empty()) continue;
    // Which eyes this view sees, and how large.
    bool any = false;
    double radius_px[2] = {0, 0};
    for (int e = 0; e < 2; ++e) {
      const glm::dvec3 outward = glm::normalize(fitted[e] - search.head_centre);
      const glm::dvec3 to_camera = glm::normalize(cam.centre() - fitted[e]);
      const glm::dvec3 p = cam.project(fitted[e]);
      if (glm::dot(outward, to_camera) < std::cos(70.0 * M_PI / 180.0) || p.z <= 0) continue;
      radius_px[e] = cam.fx * search.eye_radius / p.z;
      if (radius_px[e] < 0.75) radius_px[e] = 0;  // not resolved: under 1.5 pixels across
      any = any || radius_px[e] > 0;
    }
    if (!any) continue;
    ++out.views_facing;
    const FaceImage face = face_image_of(cam);
    for (int e = 0; e < 2; ++e) {
      if (radius_px[e] <= 0) continue;
      const glm::dvec3 p = cam.project(fitted[e]);
      // The fit's eyes may be a third of the eye distance off each: search that far.
      const double search_px = std::max(2.0 * radius_px[e], cam.fx * 0.3 * eye_distance / p.z);
      const std::vector<BlobHit> hits =
          find_eye_blobs(face, glm::dvec2(p), search_px, kOpeningFraction * radius_px[e], kMinEyeContrast, kCandidatesPerView);
      for (const BlobHit& hit : hits) seen[e].push_back({v, hit.pixel, hit.contrast * hit.roundness});
      if (!hits.empty()) radii_px.push_back(kOpeningFraction * radius_px[e]);
    }
  }
  std::sort(radii_px.begin(), radii_px.end());
  const double typical_radius = radii_px.empty() ? 1.0 : radii_px[radii_px.size() / 2];
  const double max_error = std::max(1.5, 0.75 * typical_radius);
  // Each eye's hypotheses; one placed far from where the fit puts it is another dark spot (a nostril,
  // an ear's shadow).
  std::vector<TriangulatedPoint> hypotheses[2];
  std::string reasons[2];
  for (int e = 0; e < 2; ++e) {
    std::vector<TriangulatedPoint> all = triangulate_hypotheses(scene.cameras, seen[e], max_error, kHypothesesPerEye);
    if (all.empty()) reasons[e] = triangulate(scene.cameras, seen[e], max_error).reason;
    for (TriangulatedPoint& t : all) {
      const double off = glm::distance(*t.position, fitted[e]) / eye_distance;
      if (off <= 0.5) hypotheses[e].push_back(std::move(t));
      else if (reasons[e].empty()) reasons[e] = "found " + std::to_string(off) + " eye distances from the fitted eye: another dark spot";
    }
  }
  out.hypotheses[0] = hypotheses[0], out.hypotheses[1] = hypotheses[1];
  // The pair whose views score most, the two eyes mirror images across the fitted head's middle (a
  // stripe or patch beside one eye is not mirrored beside the other). Any such pair before one eye
  // alone, which gives no distance.
  const glm::dvec3 middle = 0.5 * (search.left + search.right), across = glm::normalize(search.left - search.right);
  const auto mirrored = [&](const glm::dvec3& x) { return x - 2.0 * glm::dot(x - middle, across) * across; };
  int best[2] = {-1, -1};
  std::tuple<bool, double> best_score(false, -1.0);
  for (int a = -1; a < int(hypotheses[0].size()); ++a)
    for (int b = -1; b < int(hypotheses[1].size()); ++b) {
      if (a < 0 && b < 0) continue;
      const bool pair = a >= 0 && b >= 0;
      if (pair &&
          glm::distance(mirrored(*hypotheses[0][std::size_t(a)].position), *hypotheses[1][std::size_t(b)].position) > kMaxEyeAsymmetry * eye_distance)
        continue;
      const double score = (a >= 0 ? hypotheses[0][std::size_t(a)].score : 0.0) + (b >= 0 ? hypotheses[1][std::size_t(b)].score : 0.0);
      if (std::tuple(pair, score) > best_score) best_score = {pair, score}, best[0] = a, best[1] = b;
    }
  for (int e = 0; e < 2; ++e) {
    TriangulatedPoint& t = e == 0 ? out.left : out.right;
    if (best[e] >= 0) t = hypotheses[e][std::size_t(best[e])];
    else t.reason = !hypotheses[e].empty() ? "no hypothesis mirrors the other eye's" : reasons[e];
  }
  return out;
}

json to_json(const TriangulatedPoint& p, const std::vector<io::Camera>& cameras) {
  json views = json::array();
  for (std::uint32_t v : p.views) views.push_back(cameras[v].name);
  json j{{"views", views}, {"reprojection_rms_px", p.reprojection_rms_px}, {"score", p.score}};
  j["position"] = p.position ? json_vec3(*p.position) : json();
  if (!p.reason.empty()) j["reason"] = p.reason;
  return j;
}

}  // namespace nf::body
