#pragma once
// The two photos a vision-language model sees: a frontal and a side view, chosen from the cameras
// with the fitted body's animal frame (the camera most in front of the head, the one most to the
// animal's side; cameras whose mask touches the image border lose to ones that see the whole
// animal), each cropped to its mask's bounding box and shrunk to at most `max_side` pixels. On the
// side view the animal frame's axes are drawn from the frame's origin (x red, y green, z blue), so
// the model sees the coordinate system it is asked about.
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"

namespace nf::knowledge {

struct AnnotationPhoto {
  std::uint32_t camera = 0;
  io::Image image;    // RGB, cropped and shrunk
  std::string jpeg;   // its bytes as sent
  std::string data_url() const;
};

struct AnnotationPhotos {
  AnnotationPhoto frontal, side_with_axes;
};

// `animal_to_world`: columns left, up, forward (scaled alike) and the origin (body stage's
// animal_frame.json). Throws InputError when the scene has fewer than 1 camera with an image.
AnnotationPhotos annotation_photos(const io::Scene& scene, const glm::dmat4& animal_to_world, std::uint32_t max_side);

// Draws a line of `width` pixels (RGB image), clipped to the image.
void draw_line(io::Image& image, glm::dvec2 a, glm::dvec2 b, double width, const glm::vec3& colour);

}  // namespace nf::knowledge
