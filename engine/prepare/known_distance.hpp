#pragma once
// The scene's unit from a distance the user knows: two points they can find in the photos (the ends
// of a ruler on the floor, two marks on a collar, a tile's corners), each picked in two or more
// photos, and the distance between them in cm. Each point is triangulated from its rays through the
// cameras COLMAP found; the distance between the two, in COLMAP's unit, gives cm per unit.
//
// The file (JSON), pixel coordinates as an image viewer shows them on the original photos (column,
// row from the top-left corner; the lens distortion COLMAP found is taken out here):
//   {"cm": 30, "points": [{"IMG_0001.jpg": [812, 1400], "IMG_0007.jpg": [640, 1388]},
//                         {"IMG_0001.jpg": [1630, 1422], "IMG_0009.jpg": [1210, 1451]}]}
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"

namespace nf::prepare {

struct KnownDistance {
  double cm = 0;
  std::vector<std::map<std::string, glm::dvec2>> points;  // two: photo name -> picked pixel
};

// InputError naming the file and the field: not two points, a point seen in fewer than two photos,
// a distance that is not a positive number.
KnownDistance read_known_distance(const std::filesystem::path& file);

// A lens as COLMAP's cameras.txt states it (before undistortion).
struct Lens {
  std::string model;
  std::vector<double> params;
  // The normalised, undistorted image coordinates (x right, y down, z = 1) of a pixel. InputError
  // for a model other than SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV.
  glm::dvec2 normalised(const glm::dvec2& pixel) const;
  std::uint64_t width = 0, height = 0;  // the photos' size in pixels
};

// Each camera's lens, by COLMAP's camera id, from a text model's cameras.txt.
std::map<long long, Lens> read_colmap_cameras(const std::filesystem::path& cameras_txt);

// Each photo's lens, by photo name, from a text model (cameras.txt and images.txt).
std::map<std::string, Lens> read_lenses(const std::filesystem::path& text_model);

// cm per unit of `cameras`' frame (pinhole cameras named by their photos' stems, any rigid frame).
// Returns the report: the distance in units, each point's reprojection error per photo and the
// widest angle between its rays. InputError naming the photo when a pick lies far from where the
// other photos put the point, or when a point's rays are too close to parallel to place it.
json scale_from_known_distance(const KnownDistance& known, const std::map<std::string, Lens>& lenses, const std::vector<io::Camera>& cameras,
                               const std::string& source);

}  // namespace nf::prepare
