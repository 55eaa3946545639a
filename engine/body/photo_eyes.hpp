#pragma once
// The eyes found in the photos rather than taken from the template: the fitted face says where to
// look in each view that sees it, the eye is the blob there that differs most from the fur around
// it in colour (a dark pupil and rim, a coloured iris, a highlight), and the detections of several
// views are triangulated, the views that disagree dropped: an individual's eyes, not its kind's.
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
};

// The blob of radius `radius` (pixels), centred within `search_radius` of `centre`, whose mean
// colour differs most from its surround's (a square of half-side `radius` against the square ring
// out to twice it), refined to sub-pixel. Blobs whose ring leaves the mask are skipped (the silhouette's edge is
// not an eye). None when no candidate reaches `min_contrast`.
std::optional<BlobHit> find_eye_blob(const FaceImage& image, glm::dvec2 centre, double search_radius, double radius,
                                      double min_contrast);

// The least colour distance (RGB in [0, 1]) between an eye and the fur around it: above a photo's
// noise averaged over a few pixels, below an olive iris in brown fur (0.27).
inline constexpr double kMinEyeContrast = 0.05;

struct EyeObservation {
  std::uint32_t view = 0;
  glm::dvec2 pixel{0.0};
};

struct TriangulatedPoint {
  std::optional<glm::dvec3> position;  // none with fewer than two agreeing views
  std::vector<std::uint32_t> views;    // the views kept
  double reprojection_rms_px = 0;      // over the views kept
  std::string reason;                  // why there is no position
};

// The point closest to every observation's ray, views whose reprojection error exceeds
// `max_error_px` dropped worst first; at least two views whose rays meet at `min_angle_deg` or more.
TriangulatedPoint triangulate(const std::vector<io::Camera>& cameras, const std::vector<EyeObservation>& observations,
                              double max_error_px, double min_angle_deg = 5.0);

struct EyeSearch {
  glm::dvec3 left, right;  // the fitted eye centres (world)
  glm::dvec3 head_centre;  // the eyes face away from it
  double eye_radius = 0;   // world units
};

struct PhotoEyes {
  TriangulatedPoint left, right;
  std::uint32_t views_facing = 0;  // views that see the face
  std::optional<double> distance() const;
};

// Searches every view that faces the fitted eyes (their outward direction within 70 degrees of the
// camera) and resolves them (at least 1.5 pixels across), one photo in memory at a time.
PhotoEyes find_eyes_in_photos(const io::Scene& scene, const EyeSearch& search);

json to_json(const TriangulatedPoint& point, const std::vector<io::Camera>& cameras);

}  // namespace nf::body
