// The eyes found in the photos (engine/body/photo_eyes.hpp): a blob located to a fraction of a pixel
// under noise, by its darkness or by its colour alone, at its disc's centre when shaded or wider than
// the filter, beside a larger dark distractor, the silhouette's edge refused, and
// triangulation that keeps the views that agree, drops a wrong detection, and reports its error;
// several candidates a view (a round eye ranked above a stripe), and the two eyes chosen as mirror images.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/body/photo_eyes.hpp"
#include "engine/io/image.hpp"

using namespace nf;
using namespace nf::body;

namespace {

// A light, noisy face with a dark disc (radius r, anti-aliased by 4 x 4 samples) at `eye`; `shade`
// darkens the disc's lower half by that much more (an eyeball lit from above).
FaceImage face_with_eye(glm::dvec2 eye, double r, unsigned seed, double noise = 0.02, float shade = 0.0f) {
  FaceImage g;
  g.width = g.height = 64;
  g.rgb.assign(64 * 64, glm::vec3(0.6f));
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, float(noise));
  for (std::uint32_t y = 0; y < 64; ++y)
    for (std::uint32_t x = 0; x < 64; ++x) {
      float dark = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const glm::dvec2 at(x + (sx + 0.5) / 4, y + (sy + 0.5) / 4);
          if (glm::distance(at, eye) < r) dark += (0.35f + (at.y > eye.y ? shade : 0.0f)) / 16.0f;
        }
      g.rgb[y * 64 + x] = glm::vec3(0.6f - dark + n(rng));
    }
  return g;
}

io::Camera camera_looking_at(glm::dvec3 from, glm::dvec3 at) {
  io::Camera c;
  c.width = c.height = 512;
  c.fx = c.fy = 600, c.cx = c.cy = 256;
  c.camera_to_world = glm::inverse(glm::lookAt(from, at, glm::dvec3(0, 1, 0)));
  return c;
}

// `count` cameras 2 units from `at`, a little above it, from `first` radians round it in steps of `step`.
std::vector<io::Camera> cameras_round(glm::dvec3 at, int count, double first, double step) {
  std::vector<io::Camera> cameras;
  for (int k = 0; k < count; ++k) {
    const double a = first + step * k;
    cameras.push_back(camera_looking_at(at + 2.0 * glm::dvec3(std::sin(a), 0.3, std::cos(a)), at));
  }
  return cameras;
}

}  // namespace


TEST_CASE("a dark round blob is found to a fraction of a pixel, under noise, at the eye's size") {
  for (const double r : {1.5, 3.0}) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      CAPTURE(r);
      CAPTURE(seed);
      const glm::dvec2 eye(30.3 + 0.37 * seed, 28.6 - 0.21 * seed);
      const FaceImage g = face_with_eye(eye, r, seed);
      const auto hit = find_eye_blob(g, eye + glm::dvec2(4.0, -3.0), 8.0, r, 0.05);  // the fit's guess 5 px off
      REQUIRE(hit.has_value());
      CHECK(glm::distance(hit->pixel, eye) < 0.35);
      CHECK(hit->contrast > 0.1);
    }
  }
}

TEST_CASE("a shaded eye (its lower half darker) is found at its disc's centre, not pulled to the shade") {
  for (const double r : {2.0, 3.0}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      CAPTURE(r);
      CAPTURE(seed);
      const glm::dvec2 eye(31.2 + 0.29 * seed, 30.7 - 0.17 * seed);
      const FaceImage g = face_with_eye(eye, r, seed, 0.02, 0.2f);  // the lower half 0.55 below the face, the upper 0.35
      const auto hit = find_eye_blob(g, eye + glm::dvec2(-3.0, 2.0), 8.0, r, 0.05);
      REQUIRE(hit.has_value());
      CHECK(glm::distance(hit->pixel, eye) < 0.25);
    }
  }
}

TEST_CASE("an eye larger than the filter (an individual's, not the template's) is found at its disc's centre") {
  for (const double scale : {1.3, 1.6}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      CAPTURE(scale);
      CAPTURE(seed);
      const double filter = 2.5, r = scale * filter;
      const glm::dvec2 eye(31.4 + 0.31 * seed, 30.2 - 0.23 * seed);
      const FaceImage g = face_with_eye(eye, r, seed, 0.02, 0.1f);  // shaded, lower half darker
      const auto hit = find_eye_blob(g, eye + glm::dvec2(3.0, -2.0), 10.0, filter, 0.05);
      REQUIRE(hit.has_value());
      CHECK(glm::distance(hit->pixel, eye) < 0.35);
    }
  }
}

TEST_CASE("an eye of the fur's brightness is found by its colour (an olive iris in brown fur)") {
  FaceImage g;
  g.width = g.height = 48;
  const glm::vec3 fur(0.67f, 0.35f, 0.20f), iris(0.47f, 0.43f, 0.12f);  // both of luminance 0.41
  g.rgb.assign(48 * 48, fur);
  const glm::dvec2 eye(21.7, 25.2);
  for (std::uint32_t y = 0; y < 48; ++y)
    for (std::uint32_t x = 0; x < 48; ++x)
      if (glm::distance(glm::dvec2(x + 0.5, y + 0.5), eye) < 2.5) g.rgb[y * 48 + x] = iris;
  const auto hit = find_eye_blob(g, {25, 22}, 7.0, 2.5, 0.05);
  REQUIRE(hit.has_value());
  CHECK(glm::distance(hit->pixel, eye) < 0.6);
}

TEST_CASE("a round eye outranks a darker stripe beside it, which stays a candidate") {
  // An olive eye (radius 2.5) in orange fur, and 5 px below it a black stripe across the window:
  // the stripe differs more from the fur, but runs on along itself.
  FaceImage g;
  g.width = g.height = 48;
  const glm::vec3 fur(0.84f, 0.47f, 0.16f), iris(0.47f, 0.43f, 0.12f), stripe(0.11f, 0.10f, 0.10f);
  g.rgb.assign(48 * 48, fur);
  const glm::dvec2 eye(23.4, 21.6);
  for (std::uint32_t y = 0; y < 48; ++y)
    for (std::uint32_t x = 0; x < 48; ++x) {
      const glm::dvec2 at(x + 0.5, y + 0.5);
      if (glm::distance(at, eye) < 2.5) g.rgb[y * 48 + x] = iris;
      if (std::fabs(at.y - (eye.y + 5.5 + 0.15 * (at.x - eye.x))) < 1.5) g.rgb[y * 48 + x] = stripe;
    }
  const std::vector<BlobHit> hits = find_eye_blobs(g, {24, 23}, 7.0, 2.0, 0.05, 4);
  REQUIRE(hits.size() >= 2);
  CHECK(glm::distance(hits[0].pixel, eye) < 0.6);
  CHECK(hits[0].roundness > 0.5);
  // The stripe's best blob is the strongest contrast of all, and is found, ranked below the eye.
  const auto strongest = std::max_element(hits.begin(), hits.end(), [](const BlobHit& a, const BlobHit& b) { return a.contrast < b.contrast; });
  CHECK(strongest != hits.begin());
  CHECK(strongest->roundness < hits[0].roundness);
  // The single best is the same eye.
  const auto one = find_eye_blob(g, {24, 23}, 7.0, 2.0, 0.05);
  REQUIRE(one.has_value());
  CHECK(glm::distance(one->pixel, hits[0].pixel) < 1e-9);
}

TEST_CASE("the search stays in its window and on the animal; a face without an eye gives none") {
  FaceImage g = face_with_eye({20, 20}, 2.0, 3);
  // A darker blob of the eye's size just outside the search disc (but inside the filters' reach)
  // is not taken.
  for (std::uint32_t y = 29; y < 33; ++y)
    for (std::uint32_t x = 29; x < 33; ++x) g.rgb[y * 64 + x] = glm::vec3(0.0f);
  const auto hit = find_eye_blob(g, {22, 22}, 6.0, 2.0, 0.05);
  REQUIRE(hit.has_value());
  CHECK(glm::distance(hit->pixel, glm::dvec2(20, 20)) < 0.5);
  // The silhouette's edge (dark background beyond the mask) is not an eye.
  FaceImage edge = face_with_eye({-100, -100}, 2.0, 4);
  edge.mask.assign(64 * 64, 1);
  for (std::uint32_t y = 0; y < 64; ++y)
    for (std::uint32_t x = 40; x < 64; ++x) edge.rgb[y * 64 + x] = glm::vec3(0.0f), edge.mask[y * 64 + x] = 0;
  CHECK_FALSE(find_eye_blob(edge, {38, 32}, 6.0, 2.0, 0.05).has_value());
  CHECK_FALSE(find_eye_blob(face_with_eye({-100, -100}, 2.0, 5), {32, 32}, 8.0, 2.0, 0.05).has_value());
}

TEST_CASE("triangulation keeps the views that agree, drops a wrong detection, and needs two views apart") {
  const glm::dvec3 eye(0.1, 1.2, -0.3);
  const std::vector<io::Camera> cameras = cameras_round(eye, 6, -0.6, 0.24);
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 0.3);
  std::vector<EyeObservation> seen;
  for (std::uint32_t v = 0; v < cameras.size(); ++v) {
    glm::dvec2 p(cameras[v].project(eye));
    p += glm::dvec2(n(rng), n(rng));
    if (v == 2) p += glm::dvec2(14.0, -9.0);  // a nostril taken for the eye
    seen.push_back({v, p});
  }
  const TriangulatedPoint t = triangulate(cameras, seen, 1.5);
  REQUIRE(t.position.has_value());
  CHECK(glm::distance(*t.position, eye) < 0.002);
  CHECK(t.views.size() == 5);
  CHECK(std::find(t.views.begin(), t.views.end(), 2u) == t.views.end());
  CHECK(t.reprojection_rms_px < 0.8);
  // One view is not enough; two from the same place are not either.
  CHECK_FALSE(triangulate(cameras, {seen[0]}, 1.5).position.has_value());
  const std::vector<io::Camera> twins{cameras[0], cameras[0]};
  const TriangulatedPoint same = triangulate(twins, {{0, seen[0].pixel}, {1, seen[0].pixel}}, 1.5);
  CHECK_FALSE(same.position.has_value());
  CHECK_FALSE(same.reason.empty());
  // Two views 2 degrees apart agree, but meet at too narrow an angle to place the eye in depth.
  const std::vector<io::Camera> close{camera_looking_at(eye + 2.0 * glm::dvec3(0, 0.3, 1), eye),
                                      camera_looking_at(eye + 2.0 * glm::dvec3(std::sin(0.035), 0.3, std::cos(0.035)), eye)};
  const TriangulatedPoint narrow =
      triangulate(close, {{0, glm::dvec2(close[0].project(eye))}, {1, glm::dvec2(close[1].project(eye))}}, 1.5);
  CHECK_FALSE(narrow.position.has_value());
  CHECK(narrow.reason.find("degrees") != std::string::npos);
}

TEST_CASE("triangulation from several candidates a view: the eye most views agree on, then the next point") {
  const glm::dvec3 eye(0.1, 1.2, -0.3), spot(0.14, 1.17, -0.28);  // the eye, and a round spot 5 cm beside it
  const std::vector<io::Camera> cameras = cameras_round(eye, 7, -0.7, 0.23);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 0.3);
  std::uniform_real_distribution<double> u(-40.0, 40.0);
  std::vector<EyeObservation> seen;
  for (std::uint32_t v = 0; v < cameras.size(); ++v) {
    const auto at = [&](const glm::dvec3& x) { return glm::dvec2(cameras[v].project(x)) + glm::dvec2(n(rng), n(rng)); };
    if (v != 3) seen.push_back({v, at(eye), 0.2});                   // six views see the eye
    if (v % 2 == 0) seen.push_back({v, at(spot), 0.3});              // four see the spot, each better than the eye
    seen.push_back({v, at(eye) + glm::dvec2(u(rng), u(rng)), 0.5});  // and every view one stray blob, the best of all
  }
  // The eye's six views outscore the spot's four and any stray pair; each view agrees through one candidate.
  const TriangulatedPoint t = triangulate(cameras, seen, 1.5);
  REQUIRE(t.position.has_value());
  CHECK(glm::distance(*t.position, eye) < 0.002);
  CHECK(t.views.size() == 6);
  CHECK(t.score == doctest::Approx(1.2).epsilon(0.35));  // the eye's six (a stray may sit near it in a view)
  const std::vector<TriangulatedPoint> all = triangulate_hypotheses(cameras, seen, 1.5, 4);
  REQUIRE(all.size() >= 2);
  CHECK(glm::distance(*all[0].position, eye) < 0.002);
  CHECK(glm::distance(*all[1].position, spot) < 0.002);
  CHECK(all[1].views.size() == 4);
  // What one hypothesis explains is not used again.
  for (std::size_t k = 2; k < all.size(); ++k) CHECK(glm::distance(*all[k].position, eye) > 0.01);
}

namespace {

// A face seen by seven cameras from -54 to +54 degrees; each photo a light face with dark discs
// (world centre, world radius, grey level) drawn where the camera sees them.
struct Disc {
  glm::dvec3 centre;
  double radius;
  float grey;
};

io::Scene rig_of_photos(const std::filesystem::path& dir, const std::vector<Disc>& discs) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  io::Scene scene;
  for (int k = 0; k < 7; ++k) {
    const double a = (-54.0 + 18.0 * k) * M_PI / 180.0;
    io::Camera c = camera_looking_at(0.5 * glm::dvec3(std::sin(a), 0.2, std::cos(a)), {0, 0, 0});
    c.name = "view" + std::to_string(k);
    io::Image photo;
    photo.width = c.width, photo.height = c.height, photo.channels = 3;
    photo.pixels.assign(std::size_t(c.width) * c.height * 3, 0.6f);
    for (const Disc& d : discs) {
      if (glm::dot(glm::normalize(d.centre), glm::normalize(glm::dvec3(c.camera_to_world[3]) - d.centre)) < 0.2) continue;  // turned away
      const glm::dvec3 p = c.project(d.centre);
      const double r = c.fx * d.radius / p.z;
      for (std::uint32_t y = 0; y < c.height; ++y)
        for (std::uint32_t x = 0; x < c.width; ++x)
          if (glm::distance(glm::dvec2(x + 0.5, y + 0.5), glm::dvec2(p)) < r)
            for (std::size_t ch = 0; ch < 3; ++ch) photo.pixels[(std::size_t(y) * c.width + x) * 3 + ch] = d.grey;
    }
    c.image = dir / (c.name + ".png");
    io::write_png(c.image, photo);
    scene.cameras.push_back(c);
  }
  return scene;
}

}  // namespace

TEST_CASE("eyes found in photos: a rig of views round a face with two eyes, the fit's eyes 1 cm off") {
  // The two eyes: 1 cm radius, 6 cm apart.
  const glm::dvec3 eyes[2] = {{0.03, 0.0, 0.05}, {-0.03, 0.0, 0.05}};
  const double eye_radius = 0.01;
  const auto dir = std::filesystem::temp_directory_path() / "nf_test_photo_eyes";
  const io::Scene scene = rig_of_photos(dir, {{eyes[0], eye_radius, 0.15f}, {eyes[1], eye_radius, 0.15f}});
  const EyeSearch search{eyes[0] + glm::dvec3(0.006, 0.004, -0.006), eyes[1] + glm::dvec3(-0.008, -0.003, 0.004), {0, 0, 0}, eye_radius};
  const PhotoEyes found = find_eyes_in_photos(scene, search);
  CHECK(found.views_facing == 7);
  REQUIRE(found.left.position.has_value());
  REQUIRE(found.right.position.has_value());
  CHECK(glm::distance(*found.left.position, eyes[0]) < 0.002);
  CHECK(glm::distance(*found.right.position, eyes[1]) < 0.002);
  REQUIRE(found.distance().has_value());
  CHECK(*found.distance() == doctest::Approx(0.06).epsilon(0.03));
  CHECK(found.left.views.size() >= 4);
  CHECK(found.left.reprojection_rms_px < 1.0);
  std::filesystem::remove_all(dir);
}

TEST_CASE("eyes found in photos: a darker spot beside one eye, not mirrored beside the other, is not taken") {
  // The fit's eyes 0.9 cm off, mirror images of each other; a black round spot 2.9 cm from the left eye,
  // towards where the fit guessed it: the views rank it above the eye. The two eyes mirror each other
  // across the head; the spot and the right eye do not.
  const glm::dvec3 eyes[2] = {{0.03, 0.0, 0.05}, {-0.03, 0.0, 0.05}};
  const glm::dvec3 off(0.006, 0.004, -0.006), spot = eyes[0] + 2.9 / 0.94 * off;
  const double eye_radius = 0.01;
  const auto dir = std::filesystem::temp_directory_path() / "nf_test_photo_eyes_spot";
  const io::Scene scene = rig_of_photos(dir, {{eyes[0], eye_radius, 0.15f}, {eyes[1], eye_radius, 0.15f}, {spot, eye_radius, 0.0f}});
  const EyeSearch search{eyes[0] + off, eyes[1] + glm::dvec3(-off.x, off.y, off.z), {0, 0, 0}, eye_radius};
  const PhotoEyes found = find_eyes_in_photos(scene, search);
  // The spot is one of the left eye's hypotheses, the best supported.
  REQUIRE(found.hypotheses[0].size() >= 2);
  CHECK(glm::distance(*found.hypotheses[0][0].position, spot) < 0.005);
  REQUIRE(found.left.position.has_value());
  REQUIRE(found.right.position.has_value());
  CHECK(glm::distance(*found.left.position, eyes[0]) < 0.002);
  CHECK(glm::distance(*found.right.position, eyes[1]) < 0.002);
  std::filesystem::remove_all(dir);
}
