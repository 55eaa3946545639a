#pragma once
// The fur stage's one-way chamfer on the GPU (maths: strand_chamfer_ref.hpp): points sampled on
// M_NeuS find their nearest strand point through a uniform grid of cells rebuilt every step (a
// counting sort of the strand points by cell, then a ring search per query that
// stops once no farther cell can hold a closer point: exact, ties to the lowest index). The adjoint
// sorts the queries by their nearest point and the first query of each run sums the run into that
// point's gradient, so no float atomics and a deterministic result. Shaders: shaders/fur/chamfer_*.comp.
#include <array>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "engine/fur/strand_chamfer_ref.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::fur {

// Cubic cells over a box: `cells` along its longest side (the fur stage: M_NeuS's box grown by the
// longest fur). Points outside are searched from the border cells, still exactly. A query is
// matched when a strand point lies within max_rings cells (reach()); the fur stage picks the cell
// so that strands near the skin are well inside that reach. Cells should hold a few hundred points
// at most and max_rings stay at most kMaxChamferRings: on lavapipe all of a query's loops together
// must stay below 65,535 iterations (docs/gpu-runtime.md); 1.5 M points on the fur stage's grid is
// tested.
struct ChamferGrid {
  std::array<std::int32_t, 3> dims{1, 1, 1};
  glm::vec3 origin{0.f};
  float cell = 1;
  std::int32_t max_rings = 8;  // queries farther than max_rings cells from every strand point are unmatched
  double reach() const { return double(max_rings) * double(cell); }
  std::uint32_t cell_count() const { return std::uint32_t(dims[0] * dims[1] * dims[2]); }
};
// InputError for an empty or non-finite box or cells outside 1..256.
ChamferGrid chamfer_grid(glm::vec3 lo, glm::vec3 hi, int cells = 64);
// The grid for `points` strand points over a fur of `area` (scene units squared) in the box: cells
// holding about 100 points where the fur is (a query then walks one cell, or its 27 neighbours,
// of short runs; measured fastest on lavapipe against 230 and 60), 16..256 along the longest side,
// and as many rings as reach `reach` (4..kMaxChamferRings), fewer cells where the reach would
// need more rings than that. With no area: 64 cells.
ChamferGrid chamfer_grid_for(glm::vec3 lo, glm::vec3 hi, std::uint64_t points, double area, double reach);
// A query's search visits up to (2 rings + 1)^3 cells in one invocation, and lavapipe ends an
// invocation's loops past 65,535 iterations in all (docs/gpu-runtime.md): 12 rings are 15,625
// cells, leaving room for the points in them; 20 rings of empty cells were already cut short.
inline constexpr std::int32_t kMaxChamferRings = 12;
// The adjoint sums all the queries that share a nearest point in one loop (see kMaxChamferRings).
inline constexpr std::uint64_t kMaxChamferQueries = 60000;

struct StrandChamferScratch {
  StrandChamferScratch(gpu::Context& context, std::uint64_t points, std::uint64_t queries, const ChamferGrid& grid);
  std::uint64_t points, queries;
  gpu::Buffer<std::uint32_t> point_cells, point_slots, cell_start, cell_count, nearest, query_keys, query_ids;
  gpu::Buffer<float> dist2, records;  // records: the points in cell order, x y z and the index's bits
};

// Records the nearest strand point and squared distance of every query (queries: K x 3, points:
// M x 3, the scratch's sizes).
void strand_chamfer_forward(gpu::Stream& stream, const ChamferGrid& grid, gpu::BufferRange queries, gpu::BufferRange points,
                            StrandChamferScratch& scratch);
// After the forward has run: L_chm (unmatched queries count 0) and how many queries were unmatched.
struct ChamferValue {
  double loss = 0;
  std::uint64_t unmatched = 0;
};
ChamferValue strand_chamfer_value(const StrandChamferScratch& scratch);
// Records dLoss/dpoints for Loss = weight * L_chm; needs the forward recorded before it.
void strand_chamfer_backward(gpu::Stream& stream, gpu::BufferRange queries, gpu::BufferRange points, StrandChamferScratch& scratch,
                             double weight, gpu::BufferRange grad_points, bool accumulate);

// Host conveniences; NaN/Inf refused naming the input.
ChamferValue strand_chamfer(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries, std::span<const float> points);
std::vector<float> strand_chamfer_gradient(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries,
                                           std::span<const float> points, double weight);
std::vector<std::uint32_t> strand_chamfer_nearest(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries,
                                                  std::span<const float> points);

}  // namespace nf::fur
