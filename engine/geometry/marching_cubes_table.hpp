#pragma once
// The marching-cubes case table, generated at first use by tracing the iso-contour over the six
// faces of the cube (no hand-written or copied table). Plain arrays, so a compute shader can get
// the same data as a storage buffer.
//
// Numbering (NOT the Lorensen/Bourke one):
//   corner c = x + 2y + 4z with x, y, z in {0, 1}: the corner's offset from the cube's lowest corner.
//   edges 0..3  run along x, from corner (0,y,z) to (1,y,z), for (y,z) = (0,0) (1,0) (0,1) (1,1);
//   edges 4..7  run along y, from corner (x,0,z) to (x,1,z), for (x,z) = (0,0) (1,0) (0,1) (1,1);
//   edges 8..11 run along z, from corner (x,y,0) to (x,y,1), for (x,y) = (0,0) (1,0) (0,1) (1,1).
//   So edge e runs along axis e / 4 and edge_corners[e] = {low corner, high corner}.
//   case bit c is set when corner c is inside: value < iso (a value equal to iso is outside).
//
// Construction: one vertex on each edge whose corners differ; on every face the vertices are joined
// in pairs by chords. A face with four sign changes is ambiguous: the chords always cut off the two
// inside corners (the inside corners are separated, the outside ones joined). The rule depends on
// the face's four signs only, so the two cubes sharing a face agree and the surface is watertight.
// The chords close into loops; each loop is triangulated as a fan whose apex makes no diagonal
// between two vertices of a common face (such an edge could be used by the neighbouring cube too).
// Triangles are wound so that the right-hand normal points from inside (value < iso) to outside.
// With this rule no case needs more than kMcMaxTriangles triangles.
#include <array>
#include <cstdint>

namespace nf::geometry {

inline constexpr int kMcMaxTriangles = 5;
inline constexpr int kMcRowLength = 3 * kMcMaxTriangles + 1;  // 16: -1 terminated

struct MarchingCubesTable {
  // Per case: edge-index triples of its triangles, then -1 up to the end of the row.
  std::array<std::array<std::int8_t, kMcRowLength>, 256> triangles;
  std::array<std::uint8_t, 256> triangle_count;
  // Per case: bit e set when edge e has a sign change (carries a vertex).
  std::array<std::uint16_t, 256> edge_mask;
  // Per edge: its {low, high} corner (see the numbering above).
  std::array<std::array<std::uint8_t, 2>, 12> edge_corners;
};

// The table, built once on first call (thread-safe).
const MarchingCubesTable& marching_cubes_table();

}  // namespace nf::geometry
