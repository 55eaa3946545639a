#pragma once
// Colour maths shared by the renderer, the strands' colours and their scores: the sRGB transfer
// curve (photos and PNGs are sRGB-encoded; averages and shading are done in linear light) and
// CIELAB (D65) with the CIE76 colour difference, the unit colour errors are stated in.
#include <glm/glm.hpp>

namespace nf::color {

float srgb_to_linear(float encoded);  // [0, 1] -> [0, 1]
float linear_to_srgb(float linear);   // clamped to [0, 1] first
glm::vec3 srgb_to_linear(glm::vec3 encoded);
glm::vec3 linear_to_srgb(glm::vec3 linear);

// Linear sRGB (D65) -> CIELAB (L in [0, 100]).
glm::vec3 lab_of_linear(glm::vec3 linear);
// CIE76 Delta E between two linear sRGB colours: about 2.3 is a just noticeable difference.
float delta_e(glm::vec3 linear_a, glm::vec3 linear_b);

// Relative luminance of a linear sRGB colour.
inline float luminance(glm::vec3 linear) { return 0.2126f * linear.r + 0.7152f * linear.g + 0.0722f * linear.b; }

}  // namespace nf::color
