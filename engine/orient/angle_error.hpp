#pragma once
// Agreement of an orientation map with reference orientations (e.g. the projected directions of
// ground-truth strands from a strand rasteriser, converted with orientation_of_direction()).
#include <cstdint>
#include <vector>

#include "engine/io/image.hpp"

namespace nf::orient {

// Median over the pixels with valid[i] != 0, confidence > 0 and a finite reference of the
// undirected angle difference min(|a - b| mod pi, pi - |a - b| mod pi), in degrees (in [0, 90]).
// All images are 1-channel of the same size; valid has one byte per pixel. Returns NaN when no
// pixel counts; throws InputError when the sizes differ.
float median_angle_difference_deg(const io::Image& orientation, const io::Image& confidence,
                                  const io::Image& reference_orientation, const std::vector<std::uint8_t>& valid);

}  // namespace nf::orient
