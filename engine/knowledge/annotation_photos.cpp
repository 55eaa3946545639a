#include "engine/knowledge/annotation_photos.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "engine/core/base64.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"

namespace nf::knowledge {
namespace {

struct Candidate {
  std::uint32_t camera = 0;
  double score = 0;
};

// RGB copy of an image of 1 to 4 channels (alpha dropped, grey repeated).
io::Image rgb(const io::Image& img) {
  io::Image out{img.width, img.height, 3, std::vector<float>(std::size_t(img.width) * img.height * 3)};
  for (std::size_t i = 0; i < std::size_t(img.width) * img.height; ++i)
    for (std::uint32_t c = 0; c < 3; ++c) out.pixels[i * 3 + c] = img.pixels[i * img.channels + (img.channels >= 3 ? c : 0)];
  return out;
}

struct Box {
  std::uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool touches_border = false;
};

// The mask's bounding box with a margin of a tenth of its size; the whole image without a mask.
Box subject_box(const io::Camera& cam, const io::Image& image) {
  std::vector<std::uint8_t> mask;
  if (!cam.mask.empty()) mask = io::mask_of(io::read_image(cam.mask));
  else if (image.channels == 2 || image.channels == 4) mask = io::mask_of(image);
  Box box{0, 0, image.width, image.height, false};
  if (mask.size() != std::size_t(image.width) * image.height) return box;
  std::uint32_t x0 = image.width, y0 = image.height, x1 = 0, y1 = 0;
  for (std::uint32_t y = 0; y < image.height; ++y)
    for (std::uint32_t x = 0; x < image.width; ++x)
      if (mask[std::size_t(y) * image.width + x]) x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
  if (x1 <= x0 || y1 <= y0) return box;  // an empty mask: the whole photo
  box.touches_border = x0 == 0 || y0 == 0 || x1 == image.width || y1 == image.height;
  const std::uint32_t mx = (x1 - x0) / 10 + 2, my = (y1 - y0) / 10 + 2;
  return {x0 > mx ? x0 - mx : 0, y0 > my ? y0 - my : 0, std::min(image.width, x1 + mx), std::min(image.height, y1 + my),
          box.touches_border};
}

// 5 x 7 glyphs of the axis names x, y, z.
bool glyph_pixel(int axis, int x, int y) {
  static const char* rows[3][7] = {
      {".....", ".....", "X...X", ".X.X.", "..X..", ".X.X.", "X...X"},
      {".....", ".....", "X...X", "X...X", ".XXXX", "....X", ".XXX."},
      {".....", ".....", "XXXXX", "...X.", "..X..", ".X...", "XXXXX"}};
  return rows[axis][y][x] == 'X';
}

void draw_glyph(io::Image& img, int axis, glm::dvec2 centre, int scale, const glm::vec3& colour) {
  for (int gy = 0; gy < 7; ++gy)
    for (int gx = 0; gx < 5; ++gx) {
      if (!glyph_pixel(axis, gx, gy)) continue;
      for (int sy = 0; sy < scale; ++sy)
        for (int sx = 0; sx < scale; ++sx) {
          const long x = std::lround(centre.x + (gx - 2.5) * scale + sx), y = std::lround(centre.y + (gy - 4.5) * scale + sy);
          if (x < 0 || y < 0 || x >= long(img.width) || y >= long(img.height)) continue;
          for (int c = 0; c < 3; ++c) img.pixels[(std::size_t(y) * img.width + std::size_t(x)) * 3 + std::size_t(c)] = colour[c];
        }
    }
}

// The animal frame's axes over the side view. `to_pixel` maps a world point to this image's pixels.
template <class ToPixel>
void draw_axes(io::Image& img, const glm::dmat4& animal_to_world, ToPixel to_pixel) {
  const glm::dvec3 origin(animal_to_world[3]);
  const glm::dvec2 o = to_pixel(origin);
  // Projected directions at a common small step, so foreshortening shows (x is short in a side view).
  const double step = 0.05 * glm::length(glm::dvec3(animal_to_world[0]));
  std::array<glm::dvec2, 3> d;
  double longest = 0;
  for (int a = 0; a < 3; ++a) {
    d[std::size_t(a)] = to_pixel(origin + glm::normalize(glm::dvec3(animal_to_world[a])) * step) - o;
    longest = std::max(longest, glm::length(d[std::size_t(a)]));
  }
  if (!(longest > 1e-9)) return;
  const double reach = 0.3 * std::min(img.width, img.height), width = std::max(2.0, std::max(img.width, img.height) / 200.0);
  const std::array<glm::vec3, 3> colours{glm::vec3(1, 0.1f, 0.1f), glm::vec3(0.1f, 0.85f, 0.1f), glm::vec3(0.2f, 0.45f, 1)};
  for (int pass = 0; pass < 2; ++pass)  // a dark outline first, so the arrows read on any fur
    for (int a = 0; a < 3; ++a) {
      const glm::dvec2 tip = o + d[std::size_t(a)] * (reach / longest);
      const glm::vec3 colour = pass == 0 ? glm::vec3(0.f) : colours[std::size_t(a)];
      const double w = pass == 0 ? width + 2 : width;
      draw_line(img, o, tip, w, colour);
      const double len = glm::length(tip - o);
      if (len > 4 * width) {
        const glm::dvec2 u = (tip - o) / len, n(-u.y, u.x);
        draw_line(img, tip, tip - 4 * width * u + 2.5 * width * n, w, colour);
        draw_line(img, tip, tip - 4 * width * u - 2.5 * width * n, w, colour);
      }
      if (pass == 1) {
        const glm::dvec2 dir = len > 1e-9 ? (tip - o) / len : glm::dvec2(1, 0);
        draw_glyph(img, a, tip + dir * (6 * width), int(std::max(2.0, width)), colour);
      }
    }
}

AnnotationPhoto make_photo(const io::Scene& scene, std::uint32_t k, std::uint32_t max_side, const glm::dmat4* axes) {
  const io::Camera& cam = scene.cameras[k];
  const io::Image full = io::read_image(cam.image);
  const Box box = subject_box(cam, full);
  AnnotationPhoto photo;
  photo.camera = k;
  photo.image = io::downscale_to(rgb(io::crop(full, box.x0, box.y0, box.x1, box.y1)), max_side);
  if (axes) {
    const double sx = double(photo.image.width) / double(box.x1 - box.x0), sy = double(photo.image.height) / double(box.y1 - box.y0);
    draw_axes(photo.image, *axes, [&](const glm::dvec3& p) {
      const glm::dvec3 q = cam.project(p);
      return glm::dvec2((q.x - box.x0) * sx, (q.y - box.y0) * sy);
    });
  }
  photo.jpeg = io::encode_jpeg(photo.image, 90);
  return photo;
}

}  // namespace

std::string AnnotationPhoto::data_url() const { return "data:image/jpeg;base64," + base64_encode(jpeg); }

void draw_line(io::Image& img, glm::dvec2 a, glm::dvec2 b, double width, const glm::vec3& colour) {
  const double r = 0.5 * width;
  const long x0 = std::max(0L, long(std::floor(std::min(a.x, b.x) - r))), x1 = std::min(long(img.width) - 1, long(std::ceil(std::max(a.x, b.x) + r)));
  const long y0 = std::max(0L, long(std::floor(std::min(a.y, b.y) - r))), y1 = std::min(long(img.height) - 1, long(std::ceil(std::max(a.y, b.y) + r)));
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  for (long y = y0; y <= y1; ++y)
    for (long x = x0; x <= x1; ++x) {
      const glm::dvec2 p(x + 0.5, y + 0.5);
      const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
      if (glm::length(p - (a + t * ab)) > r) continue;
      for (int c = 0; c < 3; ++c) img.pixels[(std::size_t(y) * img.width + std::size_t(x)) * img.channels + std::size_t(c)] = colour[c];
    }
}

AnnotationPhotos annotation_photos(const io::Scene& scene, const glm::dmat4& animal_to_world, std::uint32_t max_side) {
  const glm::dvec3 origin(animal_to_world[3]);
  const glm::dvec3 left = glm::normalize(glm::dvec3(animal_to_world[0])), up = glm::normalize(glm::dvec3(animal_to_world[1])),
                   forward = glm::normalize(glm::dvec3(animal_to_world[2]));
  std::vector<Candidate> front, side;
  for (std::uint32_t k = 0; k < scene.cameras.size(); ++k) {
    const io::Camera& cam = scene.cameras[k];
    if (cam.image.empty()) continue;
    const glm::dvec3 p = cam.project(origin);
    if (!(p.z > 0) || p.x < 0 || p.y < 0 || p.x > cam.width || p.y > cam.height) continue;  // must see the body
    const glm::dvec3 v = glm::normalize(glm::dvec3(cam.camera_to_world[3]) - origin);
    const double elevation = std::fabs(glm::dot(v, up));
    front.push_back({k, glm::dot(v, forward) - 0.5 * elevation});
    side.push_back({k, std::fabs(glm::dot(v, left)) - 0.5 * elevation});
  }
  if (front.empty())
    throw InputError("knowledge: no camera with an image sees the fitted body's origin, so no photo can be sent to the VLM");
  // Of the best few by direction, prefer a camera whose mask does not touch the border.
  const auto best = [&](std::vector<Candidate> c, std::uint32_t avoid) {
    std::sort(c.begin(), c.end(), [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    std::uint32_t chosen = c[0].camera == avoid && c.size() > 1 ? c[1].camera : c[0].camera;
    double chosen_score = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0, tried = 0; i < c.size() && tried < 4; ++i) {
      if (c[i].camera == avoid) continue;
      ++tried;
      const io::Camera& cam = scene.cameras[c[i].camera];
      const io::Image image = io::read_image(cam.image);
      const double score = c[i].score - (subject_box(cam, image).touches_border ? 0.6 : 0.0);
      if (score > chosen_score) chosen_score = score, chosen = c[i].camera;
    }
    return chosen;
  };
  const std::uint32_t f = best(front, std::numeric_limits<std::uint32_t>::max());
  const std::uint32_t s = best(side, scene.cameras.size() > 1 ? f : std::numeric_limits<std::uint32_t>::max());
  log::info("knowledge: photos for the VLM: frontal ", scene.cameras[f].name, ", side ", scene.cameras[s].name);
  return {make_photo(scene, f, max_side, nullptr), make_photo(scene, s, max_side, &animal_to_world)};
}

}  // namespace nf::knowledge
