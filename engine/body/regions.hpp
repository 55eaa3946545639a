#pragma once
// Body regions of the method (the paper's list, plus mane): the labels that carry fur length,
// thickness and growth direction. Region ids are indices into kRegionNames and are what meshes
// store per vertex.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace nf::body {

enum class Region : std::int32_t {
  leg_front, leg_rear, paw_pads, paws, front_paws, belly, neck, face, ears, inner_earcanal,
  under_tail, eyes, tail, nosetip, body, mane,
};
inline constexpr int kRegionCount = 16;

inline constexpr std::array<std::string_view, kRegionCount> kRegionNames = {
    "leg_front", "leg_rear", "paw_pads", "paws", "front_paws", "belly", "neck", "face", "ears",
    "inner_earcanal", "under_tail", "eyes", "tail", "nosetip", "body", "mane"};

// A paw's vertex is a pad when its normal's component along the animal's up is below -kPadFacing
// (within 53 degrees of down): the sole that meets the ground.
inline constexpr double kPadFacing = 0.6;

inline std::int32_t region_id(Region r) { return static_cast<std::int32_t>(r); }
std::optional<Region> region_from_name(std::string_view name);
// Throws InputError naming `source` when the id is outside the table.
std::string region_name(std::int32_t id, const std::string& source = "region id");

}  // namespace nf::body
