#pragma once
// Uniform Laplacian smoothing of per-vertex values over a mesh's edges: how per-region numbers
// (fur thickness, length, direction) stop stepping at region borders.
#include <cstdint>
#include <vector>

#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

// Each vertex's neighbours through the mesh's edges (sorted, no repeats).
std::vector<std::vector<std::uint32_t>> vertex_neighbours(const Mesh& mesh);

// `iterations` Jacobi steps of v <- mean of v's neighbours (and v itself) on `values`
// (`channels` floats per vertex). Vertices with active[v] == 0 keep their value and are left out
// of their neighbours' means (active empty: all vertices take part).
void smooth_vertex_values(const Mesh& mesh, std::vector<float>& values, int channels, int iterations,
                          const std::vector<std::uint8_t>& active = {});

}  // namespace nf::geometry
