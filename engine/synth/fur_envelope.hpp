#pragma once
// The fur envelope of a synthetic animal (gt/outer.ply): the surface a perfect multi-view
// reconstruction of body + fur would find. Made as the morphological closing, with radius
// `closing_radius`, of the union of the solid body and the strands: everything within the radius
// of a strand or the body is filled, cavities are filled, then the result is eroded by the same
// radius, which fills the gaps between neighbouring strands but not the space beyond their tips.
// Extracted by marching cubes on a voxel grid.
#include "engine/io/mesh.hpp"
#include "engine/io/strands.hpp"

namespace nf::synth {

struct EnvelopeOptions {
  float voxel = 0;           // scene units; 0: the larger extent / 300
  float closing_radius = 0;  // scene units; 0: 3 voxels
};

struct Envelope {
  geometry::Mesh mesh;
  float voxel = 0, closing_radius = 0;
};

Envelope fur_envelope(const geometry::Mesh& body, const io::StrandSet& strands, const EnvelopeOptions& options = {});

}  // namespace nf::synth
