// The reduced copies of the photos prepare's masks and floor checks work on (photo_mats.hpp,
// io::reduced_to): a reduced camera projects a world point where the photo's own camera does,
// scaled, and its photo is the photo's area mean at that size.
#include <doctest/doctest.h>

#include <filesystem>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/photo_mats.hpp"

using namespace nf;

TEST_CASE("photo_mats: a camera reduced to a working size sees the world where the photo does, its photo the area mean") {
  io::Camera c;
  c.name = "wide", c.width = 640, c.height = 480, c.fx = 700, c.fy = 690, c.cx = 331.5, c.cy = 236.25;
  c.camera_to_world = glm::dmat4(1.0);
  c.camera_to_world[3] = glm::dvec4(0.1, -0.2, 2.0, 1.0);
  const io::Camera r = io::reduced_to(c, 160);
  CHECK(r.width == 160);
  CHECK(r.height == 120);
  for (const glm::dvec3 p : {glm::dvec3(0.0), glm::dvec3(0.3, 0.2, -0.5), glm::dvec3(-0.4, 0.1, 0.4)}) {
    const glm::dvec3 full = c.project(p), small = r.project(p);
    CHECK(small.x == doctest::Approx(full.x / 4).epsilon(1e-12));
    CHECK(small.y == doctest::Approx(full.y / 4).epsilon(1e-12));
    CHECK(small.z == doctest::Approx(full.z));
  }
  CHECK(io::reduced_to(c, 640).width == 640);  // small enough already: the camera itself
  CHECK(io::reduced_to(c, 4000).fx == c.fx);

  // A photo of 4 x 4 blocks, each of one grey: reduced 4 times, every pixel is its block's grey.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "nf_test_photo_mats.png";
  io::Image photo{640, 480, 3, std::vector<float>(640 * 480 * 3)};
  for (std::uint32_t y = 0; y < 480; ++y)
    for (std::uint32_t x = 0; x < 640; ++x)
      for (std::uint32_t k = 0; k < 3; ++k) photo.pixels[(std::size_t(y) * 640 + x) * 3 + k] = float(((x / 4) * 7 + (y / 4) * 13) % 256) / 255.f;
  io::write_png(file, photo);
  io::Camera on_disk = c;
  on_disk.image = file;
  const cv::Mat reduced = prepare::photo_bgr(io::reduced_to(on_disk, 160));
  REQUIRE(reduced.cols == 160);
  REQUIRE(reduced.rows == 120);
  int wrong = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) wrong += reduced.at<cv::Vec3b>(y, x)[1] != (x * 7 + y * 13) % 256;
  CHECK(wrong == 0);
  CHECK(prepare::photo_bgr(on_disk).cols == 640);
  io::Camera larger = on_disk;
  larger.width = 1280, larger.height = 960;
  CHECK_THROWS_AS(prepare::photo_bgr(larger), InputError);  // a photo smaller than its camera
  std::filesystem::remove(file);
}
