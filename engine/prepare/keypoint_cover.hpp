#pragma once
// Where a photo's keypoints on the animal lie is a fact of the photo, whatever COLMAP's pose for it
// says. A right pose draws the views' hull over them; a mask that leaves most of them out was drawn
// where the pose puts the animal, not where the photo shows it (a photo registered on the
// backdrop's pattern alone, whose first cut is seeded from the same wrong pose, can pass the
// silhouette check). Counted with a grace of 1 % of the photo's longer side for the outline.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/io/scene.hpp"
#include "engine/prepare/sparse_points.hpp"

namespace nf::prepare {

struct KeypointCover {
  std::size_t seen = 0;    // the view's observations of animal points inside the photo
  std::size_t inside = 0;  // those its mask holds
  // Background keypoints (floor and far points) well inside the mask, where the animal hides the
  // background, against how many a patch of background of the mask's area holds in this photo.
  std::size_t background_inside = 0;
  double background_expected = 0;
  bool refutes() const {
    // Under 8 animal keypoints there is too little to judge them: a right mask holds most of them,
    // but 2 of 5 lay outside one (an animal point on the outline's fur, or a floor point taken for
    // the animal's). A right mask's interior holds no background keypoint but a mislabelled one
    // (none measured, where a patch of background holds 34); a mask on the backdrop holds a patch's worth.
    return (seen >= 8 && 3 * inside < seen) || (background_inside >= 5 && double(background_inside) > 0.5 * background_expected);
  }
  std::string reason() const;  // why it refutes the pose, for the user
};

// Per camera; `animal` and `background` flag the sparse points on the animal and off it, `masks` are width x height, non-zero
// where the animal is (an empty mask counts nothing).
std::vector<KeypointCover> animal_keypoint_cover(const std::vector<io::Camera>& cameras, const SparsePoints& points, const std::vector<char>& animal,
                                                 const std::vector<char>& background,
                                                 const std::vector<std::vector<std::uint8_t>>& masks);

}  // namespace nf::prepare
