#include "engine/geometry/marching_cubes_table.hpp"

#include <string>
#include <vector>

#include "engine/core/error.hpp"

namespace nf::geometry {
namespace {

struct CubeTopology {
  std::array<std::array<std::uint8_t, 2>, 12> edge_corners{};
  std::array<std::array<int, 8>, 8> edge_of{};       // corner pair -> edge, -1 when not an edge
  std::array<std::array<int, 4>, 6> face_corners{};  // counter-clockwise seen from outside the cube
  std::array<std::uint8_t, 12> edge_faces{};         // bit f set when edge lies on face f
};

CubeTopology cube_topology() {
  CubeTopology t;
  for (auto& row : t.edge_of) row.fill(-1);
  for (int axis = 0; axis < 3; ++axis) {
    const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;  // the other two axes, in increasing order
    for (int k = 0; k < 4; ++k) {
      const int e = 4 * axis + k;
      const int low = ((k & 1) << b) | (((k >> 1) & 1) << c), high = low | (1 << axis);
      t.edge_corners[e] = {std::uint8_t(low), std::uint8_t(high)};
      t.edge_of[low][high] = t.edge_of[high][low] = e;
    }
  }
  // Face 2*axis + side: the corners with bit `axis` == side. With u, v the next axes cyclically,
  // u x v = +axis, so (0,0) (1,0) (1,1) (0,1) in (u,v) is counter-clockwise seen from the +axis side.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3, f = 2 * axis + side;
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int i = 0; i < 4; ++i) {
        const int j = side ? i : 3 - i;  // the -axis side is seen from the other way
        t.face_corners[f][i] = (side << axis) | (uv[j][0] << u) | (uv[j][1] << v);
      }
      for (int i = 0; i < 4; ++i) {
        const int e = t.edge_of[t.face_corners[f][i]][t.face_corners[f][(i + 1) % 4]];
        NF_CHECK(e >= 0, "marching cubes: face corners are not adjacent");
        t.edge_faces[e] |= std::uint8_t(1u << f);
      }
    }
  return t;
}

using Triangles = std::vector<std::array<int, 3>>;

// Triangulates the loop (cyclic, orientation kept) as a fan from an apex that makes no diagonal
// between two edges on a common face. Such an apex exists for every loop of every case.
bool triangulate(const std::vector<int>& loop, const CubeTopology& t, Triangles& out) {
  const std::size_t k = loop.size();
  auto allowed = [&](int a, int b) { return (t.edge_faces[a] & t.edge_faces[b]) == 0; };
  for (std::size_t apex = 0; apex < k; ++apex) {
    bool ok = k >= 3;
    for (std::size_t j = 2; j + 1 < k && ok; ++j) ok = allowed(loop[apex], loop[(apex + j) % k]);
    if (!ok) continue;
    for (std::size_t j = 1; j + 1 < k; ++j) out.push_back({loop[apex], loop[(apex + j) % k], loop[(apex + j + 1) % k]});
    return true;
  }
  return false;
}

MarchingCubesTable build_table() {
  const CubeTopology t = cube_topology();
  MarchingCubesTable table{};
  table.edge_corners = t.edge_corners;
  for (int cs = 0; cs < 256; ++cs) {
    auto inside = [cs](int corner) { return ((cs >> corner) & 1) != 0; };
    std::array<int, 12> next;  // the chord leaving each edge vertex
    next.fill(-1);
    std::uint16_t mask = 0;
    for (int e = 0; e < 12; ++e)
      if (inside(t.edge_corners[e][0]) != inside(t.edge_corners[e][1])) mask = std::uint16_t(mask | (1u << e));
    for (int f = 0; f < 6; ++f) {
      // Sign changes in counter-clockwise order; "entering" goes from an outside to an inside corner.
      int crossing[4], entering[4], m = 0;
      for (int i = 0; i < 4; ++i) {
        const int a = t.face_corners[f][i], b = t.face_corners[f][(i + 1) % 4];
        if (inside(a) == inside(b)) continue;
        crossing[m] = t.edge_of[a][b];
        entering[m++] = inside(b);
      }
      // Each chord runs from an entering crossing to the next crossing counter-clockwise: the inside
      // corner between them lies on the chord's right, seen from outside. With four crossings this
      // cuts off each inside corner: the ambiguity rule.
      for (int i = 0; i < m; ++i) {
        if (!entering[i]) continue;
        const int j = (i + 1) % m;
        NF_CHECK(!entering[j], "marching cubes: two entering crossings in a row on a face");
        NF_CHECK(next[crossing[i]] < 0, "marching cubes: an edge vertex starts two chords");
        next[crossing[i]] = crossing[j];
      }
    }
    // The surface's boundary runs opposite to the inside face parts' counter-clockwise boundary, so
    // by Stokes the loop order gives triangles whose right-hand normal points to the outside.
    Triangles tris;
    std::uint16_t seen = 0;
    for (int e = 0; e < 12; ++e) {
      if (!((mask >> e) & 1) || ((seen >> e) & 1)) continue;
      std::vector<int> loop;
      for (int v = e; !((seen >> v) & 1); v = next[v]) {
        NF_CHECK(v >= 0, "marching cubes: open contour in case " + std::to_string(cs));
        seen = std::uint16_t(seen | (1u << v));
        loop.push_back(v);
      }
      NF_CHECK(loop.front() == e && next[loop.back()] == e, "marching cubes: contour does not close");
      NF_CHECK(triangulate(loop, t, tris), "marching cubes: no triangulation for case " + std::to_string(cs));
    }
    NF_CHECK(tris.size() <= std::size_t(kMcMaxTriangles),
             "marching cubes: case " + std::to_string(cs) + " needs " + std::to_string(tris.size()) + " triangles");
    table.triangles[cs].fill(-1);
    for (std::size_t i = 0; i < tris.size(); ++i)
      for (int j = 0; j < 3; ++j) table.triangles[cs][3 * i + j] = std::int8_t(tris[i][j]);
    table.triangle_count[cs] = std::uint8_t(tris.size());
    table.edge_mask[cs] = mask;
  }
  return table;
}

}  // namespace

const MarchingCubesTable& marching_cubes_table() {
  static const MarchingCubesTable table = build_table();
  return table;
}

}  // namespace nf::geometry
