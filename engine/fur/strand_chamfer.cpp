#include "engine/fur/strand_chamfer.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/radix_sort.hpp"

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
struct GatherPush {
  std::uint32_t count;
  float scale;
  std::uint32_t accumulate;
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

StrandChamferScratch::StrandChamferScratch(gpu::Context& context, std::uint64_t points_, std::uint64_t queries_, const ChamferGrid& grid)
    : points(points_), queries(queries_),
      point_keys(context, points_, "chamfer point cells"), point_ids(context, points_, "chamfer point ids"),
      cell_start(context, grid.cell_count(), "chamfer cell starts"), cell_end(context, grid.cell_count(), "chamfer cell ends"),
      nearest(context, queries_, "chamfer nearest points"), query_keys(context, queries_, "chamfer query keys"),
      query_ids(context, queries_, "chamfer query ids"), point_start(context, points_, "chamfer point starts"),
      point_end(context, points_, "chamfer point ends"), dist2(context, queries_, "chamfer squared distances") {
  require_count(points_, "strand points");
  require_count(queries_, "query points");
}

void strand_chamfer_forward(gpu::Stream& stream, const ChamferGrid& grid, gpu::BufferRange queries, gpu::BufferRange points,
                            StrandChamferScratch& s) {
  gpu::require_bytes(points, s.points * 12, "strand points");
  gpu::require_bytes(queries, s.queries * 12, "chamfer queries");
  gpu::Context& context = stream.context();
  stream.dispatch(context.kernel("fur/chamfer_cell_keys", {{0, 128}}), {points, s.point_keys, s.point_ids}, grid_push(grid, s.points),
                  gpu::Elements(s.points));
  gpu::radix_sort(stream, s.point_keys, s.point_ids, gpu::key_bits_for(grid.cell_count() - 1));
  stream.fill(s.cell_start, 0);
  stream.fill(s.cell_end, 0);
  stream.dispatch(context.kernel("fur/chamfer_ranges", {{0, 128}}), {s.point_keys, s.cell_start, s.cell_end},
                  CountPush{std::uint32_t(s.points)}, gpu::Elements(s.points));
  stream.dispatch(context.kernel("fur/chamfer_query", {{0, 64}}),
                  {queries, points, s.point_ids, s.cell_start, s.cell_end, s.nearest, s.dist2}, grid_push(grid, s.queries),
                  gpu::Elements(s.queries));
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
  stream.copy(s.nearest, s.query_keys);
  stream.dispatch(context.kernel("fur/chamfer_iota", {{0, 128}}), {s.query_ids}, CountPush{std::uint32_t(s.queries)},
                  gpu::Elements(s.queries));
  gpu::radix_sort(stream, s.query_keys, s.query_ids, 32);  // unmatched queries (key ~0u) sort last and own no range
  stream.fill(s.point_start, 0);
  stream.fill(s.point_end, 0);
  stream.dispatch(context.kernel("fur/chamfer_ranges", {{0, 128}}), {s.query_keys, s.point_start, s.point_end},
                  CountPush{std::uint32_t(s.queries)}, gpu::Elements(s.queries));
  const GatherPush push{std::uint32_t(s.points), float(2.0 * weight / double(s.queries)), accumulate ? 1u : 0u};
  stream.dispatch(context.kernel("fur/chamfer_gather", {{0, 128}}),
                  {queries, points, s.query_ids, s.point_start, s.point_end, grad_points}, push, gpu::Elements(s.points));
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
