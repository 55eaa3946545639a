#pragma once
// The cameras a stage renders its previews from: the first camera, then each next one looking
// most across the first (so two views show the animal from the front or side and from across).
#include <cstdint>
#include <vector>

#include "engine/io/scene.hpp"

namespace nf::pipeline {

std::vector<std::uint32_t> preview_views(const io::Scene& scene, int count);

}  // namespace nf::pipeline
