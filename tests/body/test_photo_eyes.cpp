// The eyes found in the photos (engine/body/photo_eyes.hpp): a blob located to a fraction of a pixel
// under noise, by its darkness or by its colour alone, beside a larger dark distractor, the silhouette's edge refused, and
// triangulation that keeps the views that agree, drops a wrong detection, and reports its error.
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

// A light, noisy face with a dark disc (radius r, anti-aliased by 4 x 4 samples) at `eye`.
FaceImage face_with_eye(glm::dvec2 eye, double r, unsigned seed, double noise = 0.02) {
  FaceImage g;
  g.width = g.height = 64;
  g.rgb.assign(64 * 64, glm::vec3(0.6f));
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, float(noise));
  for (std::uint32_t y = 0; y < 64; ++y)
    for (std::uint32_t x = 0; x < 64; ++x) {
      int inside = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx)
          inside += glm::distance(glm::dvec2(x + (sx + 0.5) / 4, y + (sy + 0.5) / 4), eye) < r;
      g.rgb[y * 64 + x] = glm::vec3(0.6f - 0.35f * float(inside) / 16.0f + n(rng));
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
  std::vector<io::Camera> cameras;
  for (int k = 0; k < 6; ++k) {
    const double a = -0.6 + 0.24 * k;
    cameras.push_back(camera_looking_at(eye + 2.0 * glm::dvec3(std::sin(a), 0.3, std::cos(a)), eye));
  }
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

TEST_CASE("eyes found in photos: a rig of views round a face with two eyes, the fit's eyes 1 cm off") {
  // A face seen by seven cameras from -54 to +54 degrees; each photo a light face with the two
  // eyes (1 cm radius, 6 cm apart) drawn as dark discs where the camera sees them.
  const glm::dvec3 eyes[2] = {{0.03, 0.0, 0.05}, {-0.03, 0.0, 0.05}};
  const double eye_radius = 0.01;
  const auto dir = std::filesystem::temp_directory_path() / "nf_test_photo_eyes";
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
    for (const glm::dvec3& e : eyes) {
      if (glm::dot(glm::normalize(e), glm::normalize(glm::dvec3(c.camera_to_world[3]) - e)) < 0.2) continue;  // turned away
      const glm::dvec3 p = c.project(e);
      const double r = c.fx * eye_radius / p.z;
      for (std::uint32_t y = 0; y < c.height; ++y)
        for (std::uint32_t x = 0; x < c.width; ++x)
          if (glm::distance(glm::dvec2(x + 0.5, y + 0.5), glm::dvec2(p)) < r)
            for (std::size_t ch = 0; ch < 3; ++ch) photo.pixels[(std::size_t(y) * c.width + x) * 3 + ch] = 0.15f;
    }
    c.image = dir / (c.name + ".png");
    io::write_png(c.image, photo);
    scene.cameras.push_back(c);
  }
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

