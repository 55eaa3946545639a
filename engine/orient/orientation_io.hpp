#pragma once
// Files of orientation maps: a float EXR for the pipeline and a PNG for people.
#include <filesystem>

#include "engine/orient/orientation_map.hpp"

namespace nf::orient {

// 32-bit float EXR, channel R = orientation (radians, gabor_bank.hpp convention), G = confidence
// (io::write_exr names two channels R, G; read_orientation_exr reads them back).
void write_orientation_exr(const std::filesystem::path& path, const OrientationMap& map);
// Throws InputError naming the file when it does not hold two channels.
OrientationMap read_orientation_exr(const std::filesystem::path& path);

// Visualisation: hue = doubled orientation (so theta and theta + pi, the same undirected line,
// share a colour and hue wraps continuously at 0 = 180 degrees), value = confidence divided by its
// 99th percentile over the pixels with nonzero confidence (clamped to 1), full saturation.
io::Image orientation_visualisation(const OrientationMap& map);
void write_orientation_png(const std::filesystem::path& path, const OrientationMap& map);

}  // namespace nf::orient
