#pragma once
// The baseline groom: what one gets without the photos. Each root grows a straight strand of its
// region's length along the knowledge's growth direction (projected onto the skin's tangent plane;
// the frame's tangent where that vanishes), lifted off the skin by a lying angle. The fur stage and
// its bench score the optimised groom against it.
#include <cstdint>
#include <vector>

#include "engine/fur/roots.hpp"
#include "engine/io/strands.hpp"

namespace nf::fur {

io::StrandSet baseline_groom(const Roots& roots, const std::vector<std::uint32_t>& ids, double lying_angle_deg,
                             std::uint32_t points_per_strand = 100);

}  // namespace nf::fur
