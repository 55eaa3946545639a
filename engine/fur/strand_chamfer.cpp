#include "engine/fur/strand_chamfer.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/gpu/scan.hpp"

namespace nf::fur {
namespace {

struct GridPush {
  std::uint32_t count;
  std::int32_t nx, ny, nz;
  float ox, oy, oz, cell;
  std::int32_t max_rings;
};
struct CountPush {
  std::uint32_t count;
};
struct ScatterPush {
  std::uint32_t count;
  float scale;
};

GridPush grid_push(const ChamferGrid& g, std::uint64_t count) {
  return {std::uint32_t(count), g.dims[0], g.dims[1], g.dims[2], g.origin.x, g.origin.y, g.origin.z, g.cell, g.max_rings};
}

void require_count(std::uint64_t count, const char* what) {
  if (count == 0) throw InputError(std::string("strand chamfer: no ") + what);
  if (count >= 0xffffffffull) throw InputError(std::string("strand chamfer: too many ") + what);
}

}  // namespace

ChamferGrid chamfer_grid(glm::vec3 lo, glm::vec3 hi, int cells) {
  const glm::vec3 e = hi - lo;
  const float longest = std::max({e.x, e.y, e.z});
  if (!(longest > 0) || !std::isfinite(longest) || !std::isfinite(lo.x + lo.y + lo.z))
    throw InputError("strand chamfer: the grid's box is empty or not finite");
  if (cells < 1 || cells > 256) throw InputError("strand chamfer: cells along the longest side must be 1..256");
  ChamferGrid g;
  g.cell = longest / float(cells);
  g.origin = lo;
  for (int a = 0; a < 3; ++a) g.dims[std::size_t(a)] = std::max(1, int(std::ceil(e[a] / g.cell)));
  return g;
}

ChamferGrid chamfer_grid_for(glm::vec3 lo, glm::vec3 hi, std::uint64_t points, double area, double reach) {
  const glm::vec3 e = hi - lo;
  const double longest = std::max({e.x, e.y, e.z});
  const bool has_reach = reach > 0 && std::isfinite(reach);
  int cells = 64;
  if (area > 0 && std::isfinite(area) && points > 0 && longest > 0) {
    constexpr double kPointsPerCell = 100;
    const double cell = std::sqrt(kPointsPerCell * area / double(points));
    cells = int(std::clamp(std::ceil(longest / cell), 16.0, 256.0));
  }
  if (has_reach && longest > 0) cells = std::clamp(int(std::floor(kMaxChamferRings * longest / reach)), 1, cells);
  ChamferGrid g = chamfer_grid(lo, hi, cells);
  g.max_rings = has_reach ? int(std::clamp(std::ceil(reach / double(g.cell)), 4.0, double(kMaxChamferRings))) : 8;
  return g;
}

StrandChamferScratch::StrandChamferScratch(gpu::Context& context, std::uint64_t points_, std::uint64_t queries_, const ChamferGrid& grid)
    : points(points_), queries(queries_),
      point_cells(context, points_, "chamfer point cells"), point_slots(context, points_, "chamfer point slots"),
      cell_start(context, grid.cell_count(), "chamfer cell starts"), cell_count(context, grid.cell_count(), "chamfer cell counts"),
      nearest(context, queries_, "chamfer nearest points"), query_keys(context, queries_, "chamfer query keys"),
      query_ids(context, queries_, "chamfer query ids"), dist2(context, queries_, "chamfer squared distances"),
      records(context, points_ * 4, "chamfer points by cell") {
  require_count(points_, "strand points");
  require_count(queries_, "query points");
  if (queries_ > kMaxChamferQueries)
    throw InputError("strand chamfer: " + std::to_string(queries_) + " query points, at most " + std::to_string(kMaxChamferQueries) +
                     " (fur.chamfer_queries)");
  if (grid.max_rings < 0 || grid.max_rings > kMaxChamferRings)
    throw InputError("strand chamfer: " + std::to_string(grid.max_rings) + " rings, at most " + std::to_string(kMaxChamferRings));
}

void strand_chamfer_forward(gpu::Stream& stream, const ChamferGrid& grid, gpu::BufferRange queries, gpu::BufferRange points,
                            StrandChamferScratch& s) {
  gpu::require_bytes(points, s.points * 12, "strand points");
  gpu::require_bytes(queries, s.queries * 12, "chamfer queries");
  gpu::Context& context = stream.context();
  {
    // A counting sort (atomic slots, one scan of the cells): two passes over the points where a
    // radix sort of their cell keys took five, each with its own scan.
    gpu::ScopedPass pass(stream, "fur/chamfer_grid");
    stream.fill(s.cell_count, 0);
    stream.dispatch(context.kernel("fur/chamfer_cell_count", {{0, 128}}), {points, s.point_cells, s.point_slots, s.cell_count},
                    grid_push(grid, s.points), gpu::Elements(s.points));
    gpu::exclusive_scan(stream, s.cell_count, s.cell_start);
    stream.dispatch(context.kernel("fur/chamfer_sorted_points", {{0, 128}}), {points, s.point_cells, s.point_slots, s.cell_start, s.records},
                    CountPush{std::uint32_t(s.points)}, gpu::Elements(s.points));
  }
  gpu::ScopedPass pass(stream, "fur/chamfer_query");
  stream.dispatch(context.kernel("fur/chamfer_query", {{0, 64}}), {queries, s.records, s.cell_start, s.cell_count, s.nearest, s.dist2},
                  grid_push(grid, s.queries), gpu::Elements(s.queries));
}

ChamferValue strand_chamfer_value(const StrandChamferScratch& s) {
  const std::vector<float> d = s.dist2.download();
  const std::vector<std::uint32_t> nn = s.nearest.download();
  ChamferValue v;
  for (std::size_t k = 0; k < d.size(); ++k) v.loss += double(d[k]), v.unmatched += nn[k] == kUnmatched;
  v.loss /= double(d.size());
  return v;
}

void strand_chamfer_backward(gpu::Stream& stream, gpu::BufferRange queries, gpu::BufferRange points, StrandChamferScratch& s,
                             double weight, gpu::BufferRange grad_points, bool accumulate) {
  gpu::require_bytes(grad_points, s.points * 12, "strand point gradients");
  gpu::Context& context = stream.context();
  gpu::ScopedPass pass(stream, "fur/chamfer_backward");
  if (!accumulate) stream.fill(gpu::BufferRange{grad_points.buffer, grad_points.offset, s.points * 12}, 0);
  stream.copy(s.nearest, s.query_keys);
  stream.dispatch(context.kernel("fur/chamfer_iota", {{0, 128}}), {s.query_ids}, CountPush{std::uint32_t(s.queries)},
                  gpu::Elements(s.queries));
  // Only the bits a point index needs; unmatched queries (key ~0u) keep theirs and sort last.
  gpu::radix_sort(stream, s.query_keys, s.query_ids, s.points >= 0xffffffffull ? 32 : gpu::key_bits_for(std::uint32_t(s.points)));
  const ScatterPush push{std::uint32_t(s.queries), float(2.0 * weight / double(s.queries))};
  stream.dispatch(context.kernel("fur/chamfer_scatter", {{0, 128}}), {queries, points, s.query_keys, s.query_ids, grad_points}, push,
                  gpu::Elements(s.queries));
}

namespace {

struct Run {
  gpu::Buffer<float> queries, points;
  StrandChamferScratch scratch;
};

Run forward(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries, std::span<const float> points,
            gpu::Stream& stream) {
  if (queries.size() % 3 || points.size() % 3) throw InputError("strand chamfer: points come as x, y, z triples");
  require_finite(queries, "chamfer queries");
  require_finite(points, "strand points");
  Run r{gpu::Buffer<float>(context, queries, "chamfer queries"), gpu::Buffer<float>(context, points, "strand points"),
        StrandChamferScratch(context, points.size() / 3, queries.size() / 3, grid)};
  strand_chamfer_forward(stream, grid, r.queries, r.points, r.scratch);
  return r;
}

}  // namespace

ChamferValue strand_chamfer(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries, std::span<const float> points) {
  gpu::Stream stream(context);
  Run r = forward(context, grid, queries, points, stream);
  stream.submit_and_wait();
  return strand_chamfer_value(r.scratch);
}

std::vector<float> strand_chamfer_gradient(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries,
                                           std::span<const float> points, double weight) {
  gpu::Stream stream(context);
  Run r = forward(context, grid, queries, points, stream);
  gpu::Buffer<float> grad(context, points.size(), "strand point gradients");
  strand_chamfer_backward(stream, r.queries, r.points, r.scratch, weight, grad, false);
  stream.submit_and_wait();
  return grad.download();
}

std::vector<std::uint32_t> strand_chamfer_nearest(gpu::Context& context, const ChamferGrid& grid, std::span<const float> queries,
                                                  std::span<const float> points) {
  gpu::Stream stream(context);
  Run r = forward(context, grid, queries, points, stream);
  stream.submit_and_wait();
  return r.scratch.nearest.download();
}

}  // namespace nf::fur
