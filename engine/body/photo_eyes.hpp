#pragma once
// The eyes found in the photos rather than taken from the template: the fitted face says where to
// look in each view that sees it; the eye is a round blob there that differs from the fur around it
// in colour (a dark pupil and rim, a coloured iris, a highlight). Each view offers a few such blobs,
// the views' blobs are triangulated into the points most views agree on, and the two eyes are the
// pair of points that mirror each other across the head: an individual's eyes, not its kind's.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"

namespace nf::body {

// A photo (RGB as io::read_image gives it) with its mask (empty: every pixel counts).
struct FaceImage {
  std::uint32_t width = 0, height = 0;
  std::vector<glm::vec3> rgb;
  std::vector<std::uint8_t> mask;
};

struct BlobHit {
  glm::dvec2 pixel;  // sub-pixel centre (x right, y down; pixel centres at +0.5)
  double contrast;   // the colour distance between the blob's mean and its surround's
  double roundness;  // 1: the contrast falls away alike in every direction; 0: a ridge (a stripe, an edge)
};

// Blobs of radius `radius` (pixels) centred within `search_radius` of `centre`: the peaks of the
// contrast between a square of half-side `radius` and the square ring out to twice it (the colour
// distance of their means) that reach `min_contrast`, refined to sub-pixel. Up to `max_count`,
// ranked by contrast times roundness: a stripe or a patch's edge may differ more from the fur than
// the eye, but runs on along itself. Blobs whose ring leaves the mask are skipped (the silhouette's
// edge is not an eye).
std::vector<BlobHit> find_eye_blobs(const FaceImage& image, glm::dvec2 centre, double search_radius, double radius,
                                    double min_contrast, std::size_t max_count);
// The first of them; none when no peak reaches `min_contrast`.
std::optional<BlobHit> find_eye_blob(const FaceImage& image, glm::dvec2 centre, double search_radius, double radius,
                                      double min_contrast);

// The least colour distance (RGB in [0, 1]) between an eye and the fur around it: above a photo's
// noise averaged over a few pixels, below an olive iris in brown fur (0.27).
inline constexpr double kMinEyeContrast = 0.05;

struct EyeObservation {
  std::uint32_t view = 0;
  glm::dvec2 pixel{0.0};
  double score = 0;  // the blob's contrast times its roundness
};

struct TriangulatedPoint {
  std::optional<glm::dvec3> position;  // none with fewer than two agreeing views
  std::vector<std::uint32_t> views;    // the views kept
  double reprojection_rms_px = 0;      // over the views kept
  double score = 0;                    // the kept observations' scores, summed
  std::string reason;                  // why there is no position
};

// The point closest to every observation's ray, views whose reprojection error exceeds
// `max_error_px` dropped worst first; at least two views whose rays meet at `min_angle_deg` or more.
// A view may hold several candidates; it agrees through the one nearest the point. Of the points
// that pairs of views propose, the one whose agreeing observations score most wins (then the one
// more views agree with).
TriangulatedPoint triangulate(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations,
                              double max_error_px, double min_angle_deg = 5.0);
// Up to `max_count` points, each triangulated from the observations the earlier ones did not
// explain (within `max_error_px`), the best supported first.
std::vector<TriangulatedPoint> triangulate_hypotheses(const std::vector<io::Camera>& cameras, std::vector<EyeObservation> observations,
                                                      double max_error_px, std::size_t max_count, double min_angle_deg = 5.0);

struct EyeSearch {
  glm::dvec3 left, right;  // the fitted eye centres (world)
  glm::dvec3 head_centre;  // the eyes face away from it
  double eye_radius = 0;   // world units
};

struct PhotoEyes {
  TriangulatedPoint left, right;
  std::uint32_t views_facing = 0;  // views that see the face
  std::vector<TriangulatedPoint> hypotheses[2];  // each eye's, near the fitted eye, before the pair was chosen
  std::optional<double> distance() const;
};

// Searches every view that faces the fitted eyes (their outward direction within 70 degrees of the
// camera) and resolves them (at least 1.5 pixels across), one photo in memory at a time. Each eye's
// hypotheses lie within half an eye distance of the fitted eye; the pair kept scores most of those
// whose left eye lies within 0.35 eye distances of the right's mirror image across the fitted
// head's middle (or one eye alone, when no pair does).
PhotoEyes find_eyes_in_photos(const io::Scene& scene, const EyeSearch& search);

json to_json(const TriangulatedPoint& point, const std::vector<io::Camera>& cameras);

}  // namespace nf::body
