#pragma once
// The fur's effective thickness of a synthetic animal, per region: the median distance from the
// region's vertices of the bald body to the fur envelope (gt/outer.ply). It is what a de-furring of
// a perfect reconstruction must remove to get back to the body (paper: De-furring), and what
// gt/knowledge.json states as each region's thickness_cm, so that swapping in the true knowledge
// also swaps in the true thickness. A preset's rule of thumb (0.35 x the length) does not hold for
// grown fur: lift, clumps and gravity set it (the cat's body: 0.54 x, the lion's mane: 0.20 x).
#include <array>

#include "engine/body/regions.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::synth {

// Scene units; a region without vertices on `bald` gets -1. bald.regions must hold a region per
// vertex; the envelope must have triangles.
std::array<float, body::kRegionCount> effective_thickness(const geometry::Mesh& bald, const geometry::Mesh& envelope);

}  // namespace nf::synth
