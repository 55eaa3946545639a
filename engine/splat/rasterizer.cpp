#include "engine/splat/rasterizer.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/gpu/scan.hpp"

namespace nf::splat {
namespace {

// Twin of nf_splat_camera.glsl.
struct ProjectPush {
  float r0[4], r1[4], r2[4];
  float fx, fy, cx, cy;
  std::uint32_t width, height;
  float near_plane, far_plane;
  float k2, eps2, delta2;
  float low_pass, orientation_guard;
  std::uint32_t strands, points_per_strand;
};
static_assert(sizeof(ProjectPush) == 108);

struct DepthKeysPush {
  std::uint32_t count, depth_bits;
  float near_plane, far_plane;
};
struct CountPush {
  std::uint32_t count;
};
struct KeysPush {
  std::uint32_t count, tiles_x;
};
struct RangesPush {
  std::uint32_t count, tiles;
};
struct CompositePush {
  std::uint32_t width, height, tiles_x, has_body;
  std::uint32_t walk_begin, walk_end;
  std::uint32_t long_count;
  float depth_slack;
};
struct LongestPush {
  std::uint32_t tiles, chunk;
};
struct GatherPush {
  std::uint32_t strands, points_per_strand, accumulate;
};

ProjectPush project_push(const StrandShape& shape, const RasterCamera& c, const RasterParams& p) {
  ProjectPush push{};
  for (int i = 0; i < 4; ++i)
    push.r0[i] = float(c.world_to_camera[i]), push.r1[i] = float(c.world_to_camera[4 + i]), push.r2[i] = float(c.world_to_camera[8 + i]);
  push.fx = float(c.fx), push.fy = float(c.fy), push.cx = float(c.cx), push.cy = float(c.cy);
  push.width = c.width, push.height = c.height;
  push.near_plane = float(c.near), push.far_plane = float(c.far);
  const SegmentGaussianTerms<float> t(p.gaussian);
  push.k2 = t.k2, push.eps2 = t.eps2, push.delta2 = t.delta2;
  push.low_pass = float(p.low_pass), push.orientation_guard = float(p.orientation_guard);
  push.strands = shape.strands, push.points_per_strand = shape.points_per_strand;
  return push;
}

template <class T>
void ensure(gpu::Context& context, std::unique_ptr<gpu::Buffer<T>>& buffer, std::uint64_t count, const char* name) {
  count = std::max<std::uint64_t>(count, 1);
  if (!buffer || buffer->size() < count) buffer = std::make_unique<gpu::Buffer<T>>(context, count + count / 4, name);
}

}  // namespace

void validate(const RasterCamera& c) {
  if (c.width == 0 || c.height == 0 || c.width > 16384 || c.height > 16384)
    throw InputError("raster camera: image size " + std::to_string(c.width) + "x" + std::to_string(c.height) + " is invalid");
  for (double v : {c.fx, c.fy, c.cx, c.cy})
    if (!std::isfinite(v)) throw InputError("raster camera: intrinsics are not finite");
  if (!(c.fx > 0) || !(c.fy > 0)) throw InputError("raster camera: focal lengths must be positive");
  if (!(c.near > 0) || !(c.far > c.near) || !std::isfinite(c.far))
    throw InputError("raster camera: need 0 < near < far, got near " + std::to_string(c.near) + ", far " + std::to_string(c.far));
  for (double v : c.world_to_camera)
    if (!std::isfinite(v)) throw InputError("raster camera: the pose is not finite");
}

RasterCamera raster_camera(const io::Camera& camera, double near, double far) {
  RasterCamera r;
  const glm::dmat4 w2c = glm::inverse(camera.camera_to_world);
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) r.world_to_camera[4 * row + col] = w2c[col][row];
  r.fx = camera.fx, r.fy = camera.fy, r.cx = camera.cx, r.cy = camera.cy;
  r.width = camera.width, r.height = camera.height;
  r.near = near, r.far = far;
  return r;
}

namespace {

// Compositing is laid out for GPUs (one pixel per invocation; backward sums through shared-memory
// atomics where the device has them) or for CPU devices such as lavapipe (four pixels per
// invocation, a column of rows, so a subgroup sum covers a Gaussian's gradient over 32 pixels
// instead of 8; subgroup sums straight to global atomics, since shared atomics there are per-lane
// loops and barriers switch coroutines). On lavapipe the CPU layout is 2x faster forward and 2.5x
// backward. NF_SPLAT_GPU_LAYOUT=1 takes the GPU layout on any device, so that CI runs it.
bool choose_gpu_layout(const gpu::Context& ctx) { return gpu::use_gpu_layout(ctx, "NF_SPLAT_GPU_LAYOUT"); }

std::uint32_t pixels_per_invocation(bool gpu_layout) { return gpu_layout ? 1 : 4; }

std::uint32_t composite_workgroup(bool gpu_layout) { return kTile * kTile / pixels_per_invocation(gpu_layout); }

// in_passes: the walk is split in passes (the resume code is compiled out of a single pass).
std::vector<gpu::SpecConstant> composite_spec(bool gpu_layout, bool in_passes) {
  return {{0, composite_workgroup(gpu_layout)}, {1, pixels_per_invocation(gpu_layout)}, {2, in_passes ? 1u : 0u}};
}

// Tile-list entries one compositing pass walks. A walk turns its loops about 1.25 times an entry
// (batches of 8 lanes on lavapipe; 1.5 with 4), so half the device's loop limit keeps a pass
// inside it; a device without a limit walks each list in one pass.
std::uint32_t walk_chunk_for(const gpu::Context& ctx, const RasterParams& params) {
  if (params.walk_chunk > 0) return params.walk_chunk;
  const std::uint32_t limit = ctx.tuning().loop_iterations;
  return limit > 0 ? std::max<std::uint32_t>(limit / 2, 1) : std::numeric_limits<std::uint32_t>::max();
}

// The push constants of compositing pass `pass` of `passes` (the last one walks to the list's end).
CompositePush composite_push(const RasterCamera& camera, bool has_body, std::uint32_t chunk, std::uint32_t pass,
                             std::uint32_t passes, std::uint32_t long_count) {
  const std::uint32_t begin = pass * chunk;
  const std::uint32_t end = pass + 1 == passes ? std::numeric_limits<std::uint32_t>::max() : begin + chunk;
  // Depth keys truncate depth to depth_bits between near and far (rasterize_depth_keys): a
  // Gaussian lies at most one step, plus float rounding, deeper than its key says.
  const double step = (camera.far - camera.near) / double((1ull << depth_bits(camera)) - 1);
  const float slack = float(2 * step + 1e-6 * camera.far);
  return {camera.width, camera.height, tiles_x(camera), has_body ? 1u : 0u, begin, end, long_count, slack};
}

}  // namespace

struct StrandRasterizer::Impl {
  gpu::Context& context;
  std::unique_ptr<gpu::Buffer<float>> proj, grad_proj, grad_segment, final_t, no_body, walk_carry;
  std::unique_ptr<gpu::Buffer<std::uint32_t>> touched, offsets, total, rects, keys, values, ranges, last;
  std::unique_ptr<gpu::Buffer<std::uint32_t>> walk_stats, long_tiles;  // longest list, tiles longer than a pass
  std::unique_ptr<gpu::Buffer<std::uint32_t>> depth_keys, order, sorted_touched, rank;  // depth order of the Gaussians
  // State of the last forward, for the backward.
  StrandShape shape;
  RasterCamera camera;
  RasterParams params;
  gpu::BufferRange points, body;
  std::uint64_t entries = 0;
  std::uint32_t walk_chunk = 0, walk_passes = 1, long_count = 0;  // how compositing walks the tile lists
  bool has_body = false;
  const bool gpu_layout;  // chosen once, so that forward and backward agree
  explicit Impl(gpu::Context& c) : context(c), gpu_layout(choose_gpu_layout(c)) {}
};

StrandRasterizer::StrandRasterizer(gpu::Context& context) : impl_(std::make_unique<Impl>(context)) {}
StrandRasterizer::~StrandRasterizer() = default;

std::uint64_t StrandRasterizer::tile_entries() const { return impl_->entries; }
std::uint32_t StrandRasterizer::walk_passes() const { return impl_->walk_passes; }

std::uint64_t max_segments_per_view(const gpu::Context& context) { return gpu::max_binding_elements(context, kProjected * sizeof(float)); }

void StrandRasterizer::forward(const StrandShape& shape, gpu::BufferRange points, gpu::BufferRange confidence,
                               const RasterCamera& camera, const RasterParams& params, gpu::BufferRange body_depth,
                               gpu::BufferRange image) {
  Impl& m = *impl_;
  validate(shape, params.gaussian, points.size / 4);
  validate(camera);
  const std::uint64_t segments = shape.segments(), pixels = std::uint64_t(camera.width) * camera.height;
  const std::uint64_t most = max_segments_per_view(m.context);
  if (segments > most)
    throw InputError("strands: " + std::to_string(segments) + " segments in one view; this device rasterises at most " +
                     std::to_string(most) + " (one " + std::to_string(most * kProjected * 4 / (1024 * 1024)) +
                     " MiB binding of projected Gaussians); render fewer strands per view");
  gpu::require_bytes(confidence, segments * 4, "segment confidence");
  gpu::require_bytes(image, pixels * kChannels * 4, "raster image");
  m.has_body = body_depth.buffer != nullptr;
  if (m.has_body) gpu::require_bytes(body_depth, pixels * 4, "body depth map");
  m.shape = shape, m.camera = camera, m.params = params, m.points = points;
  gpu::Context& ctx = m.context;
  ensure(ctx, m.proj, segments * kProjected, "raster projected gaussians");
  ensure(ctx, m.touched, segments, "raster tiles touched");
  ensure(ctx, m.offsets, segments, "raster tile offsets");
  ensure(ctx, m.depth_keys, segments, "raster depth keys");
  ensure(ctx, m.order, segments, "raster depth order");
  ensure(ctx, m.sorted_touched, segments, "raster tiles touched in depth order");
  ensure(ctx, m.rank, segments, "raster depth rank");
  ensure(ctx, m.total, 1, "raster tile total");
  ensure(ctx, m.rects, segments * 3, "raster tile rectangles");
  const std::uint32_t ntx = tiles_x(camera), nty = tiles_y(camera), tiles = ntx * nty;
  ensure(ctx, m.ranges, std::uint64_t(tiles) * 2, "raster tile ranges");
  ensure(ctx, m.final_t, pixels, "raster final transmittance");
  ensure(ctx, m.last, pixels, "raster last contributor");
  ensure(ctx, m.no_body, 1, "raster no body");
  m.body = m.has_body ? body_depth : m.no_body->whole();

  const ProjectPush push = project_push(shape, camera, params);
  {
    gpu::Stream stream(ctx);
    {
      gpu::ScopedPass pass(stream, "splat/rasterize_project");
      stream.dispatch(ctx.kernel("splat/rasterize_project", {{0, 128}}),
                      {points, confidence, m.proj->range(0, segments * kProjected), m.touched->range(0, segments),
                       m.rects->range(0, segments * 3)},
                      push, gpu::Elements(segments));
    }
    // Gaussians in depth order, then their tile counts in that order and the scan that places
    // their entries: the entries' stable sort by tile then keeps every tile's list front to back.
    {
      gpu::ScopedPass pass(stream, "splat/sort_depth");
      const DepthKeysPush dp{std::uint32_t(segments), depth_bits(camera), float(camera.near), float(camera.far)};
      stream.dispatch(ctx.kernel("splat/rasterize_depth_keys", {{0, 128}}),
                      {m.proj->range(0, segments * kProjected), m.depth_keys->range(0, segments), m.order->range(0, segments)},
                      dp, gpu::Elements(segments));
      gpu::radix_sort(stream, m.depth_keys->range(0, segments), m.order->range(0, segments), depth_bits(camera));
      stream.dispatch(ctx.kernel("splat/rasterize_sorted_counts", {{0, 128}}),
                      {m.order->range(0, segments), m.touched->range(0, segments), m.sorted_touched->range(0, segments),
                       m.rank->range(0, segments)},
                      CountPush{std::uint32_t(segments)}, gpu::Elements(segments));
    }
    {
      gpu::ScopedPass pass(stream, "splat/scan_tiles");
      gpu::exclusive_scan(stream, m.sorted_touched->range(0, segments), m.offsets->range(0, segments), m.total->range(0, 1));
    }
    stream.submit_and_wait();
  }
  m.entries = m.total->download(0, 1)[0];
  gpu::Stream stream(ctx);
  stream.fill(m.ranges->range(0, std::uint64_t(tiles) * 2), 0);
  if (m.entries > 0) {
    ensure(ctx, m.keys, m.entries, "raster keys");
    ensure(ctx, m.values, m.entries, "raster values");
    {
      gpu::ScopedPass pass(stream, "splat/rasterize_keys");
      const KeysPush kp{std::uint32_t(segments), ntx};
      stream.dispatch(ctx.kernel("splat/rasterize_keys", {{0, 128}}),
                      {m.proj->range(0, segments * kProjected), m.offsets->range(0, segments), m.rects->range(0, segments * 3),
                       m.keys->range(0, m.entries), m.values->range(0, m.entries), m.touched->range(0, segments),
                       m.rank->range(0, segments)},
                      kp, gpu::Elements(segments));
    }
    {
      // Tile indices: only their bits.
      gpu::ScopedPass pass(stream, "splat/sort");
      gpu::radix_sort(stream, m.keys->range(0, m.entries), m.values->range(0, m.entries), gpu::key_bits_for(tiles - 1));
    }
    {
      gpu::ScopedPass pass(stream, "splat/rasterize_ranges");
      const RangesPush rp{std::uint32_t(m.entries), tiles};
      stream.dispatch(ctx.kernel("splat/rasterize_ranges", {{0, 128}}),
                      {m.keys->range(0, m.entries), m.ranges->range(0, std::uint64_t(tiles) * 2)}, rp, gpu::Elements(m.entries));
    }
  } else {
    ensure(ctx, m.values, 1, "raster values");
  }
  // A list longer than one pass's walk needs several: the longest list says how many, and the
  // passes after the first visit only the tiles whose list is that long.
  m.walk_chunk = walk_chunk_for(ctx, params);
  m.walk_passes = 1, m.long_count = 0;
  ensure(ctx, m.walk_stats, 2, "raster walk stats");
  ensure(ctx, m.long_tiles, 1, "raster long tiles");
  if (m.entries > m.walk_chunk) {
    ensure(ctx, m.long_tiles, tiles, "raster long tiles");
    {
      gpu::ScopedPass pass(stream, "splat/rasterize_longest");
      stream.fill(m.walk_stats->range(0, 2), 0);
      stream.dispatch(ctx.kernel("splat/rasterize_longest", {{0, 128}}),
                      {m.ranges->range(0, std::uint64_t(tiles) * 2), m.walk_stats->range(0, 2), m.long_tiles->range(0, tiles)},
                      LongestPush{tiles, m.walk_chunk}, gpu::Elements(tiles));
    }
    stream.submit_and_wait();
    const std::vector<std::uint32_t> stats = m.walk_stats->download(0, 2);
    m.walk_passes = std::max<std::uint32_t>(1, std::uint32_t((std::uint64_t(stats[0]) + m.walk_chunk - 1) / m.walk_chunk));
    m.long_count = stats[1];
  }
  {
    gpu::ScopedPass pass(stream, "splat/rasterize_fwd");
    for (std::uint32_t p = 0; p < m.walk_passes; ++p)
      stream.dispatch(ctx.kernel("splat/rasterize_fwd", composite_spec(m.gpu_layout, m.walk_passes > 1)),
                      {m.proj->range(0, segments * kProjected), m.values->range(0, std::max<std::uint64_t>(m.entries, 1)),
                       m.ranges->range(0, std::uint64_t(tiles) * 2), m.body, image, m.final_t->range(0, pixels),
                       m.last->range(0, pixels), m.long_tiles->range(0, std::max<std::uint32_t>(m.long_count, 1))},
                      composite_push(camera, m.has_body, m.walk_chunk, p, m.walk_passes, m.long_count),
                      gpu::Elements(std::uint64_t(p == 0 ? tiles : m.long_count) * composite_workgroup(m.gpu_layout)));
  }
  stream.submit_and_wait();
}

void StrandRasterizer::backward(gpu::Stream& stream, gpu::BufferRange grad_image, gpu::BufferRange grad_points,
                                gpu::BufferRange grad_confidence, bool accumulate) {
  Impl& m = *impl_;
  const StrandShape& shape = m.shape;
  const RasterCamera& camera = m.camera;
  const std::uint64_t segments = shape.segments(), pixels = std::uint64_t(camera.width) * camera.height;
  if (!m.proj) throw InternalError("strand rasterizer: backward before forward");
  gpu::require_bytes(grad_image, pixels * kChannels * 4, "raster image gradient");
  gpu::require_bytes(grad_points, shape.points() * 12, "strand point gradients");
  gpu::require_bytes(grad_confidence, segments * 4, "segment confidence gradients");
  gpu::Context& ctx = m.context;
  ensure(ctx, m.grad_proj, segments * kProjected, "raster projected gradients");
  ensure(ctx, m.grad_segment, segments * 6, "raster segment gradients");
  const std::uint32_t ntx = tiles_x(camera), tiles = ntx * tiles_y(camera);
  stream.fill(m.grad_proj->range(0, segments * kProjected), 0);
  // The adjoint state handed from pass to pass when the forward walked the lists in several.
  ensure(ctx, m.walk_carry, m.walk_passes > 1 ? pixels * 6 : 1, "raster walk carry");
  {
    gpu::ScopedPass pass(stream, "splat/rasterize_bwd");
    // Shared-memory sums in the GPU layout where the device has shared float atomics (gpu_layout;
    // NF_NO_SHARED_FLOAT_ATOMICS=1 takes them away).
    const bool shared_sums = m.gpu_layout && ctx.info().features.float32_atomic_add_shared;
    const char* variant = shared_sums ? "splat/rasterize_bwd:shared" : "splat/rasterize_bwd:subgroup";
    for (std::uint32_t p = m.walk_passes; p-- > 0;)
      stream.dispatch(ctx.kernel(variant, composite_spec(m.gpu_layout, m.walk_passes > 1)),
                      {m.proj->range(0, segments * kProjected), m.values->range(0, std::max<std::uint64_t>(m.entries, 1)),
                       m.ranges->range(0, std::uint64_t(tiles) * 2), m.body, m.final_t->range(0, pixels),
                       m.last->range(0, pixels), grad_image, m.grad_proj->range(0, segments * kProjected),
                       m.walk_carry->range(0, m.walk_passes > 1 ? pixels * 6 : 1),
                       m.long_tiles->range(0, std::max<std::uint32_t>(m.long_count, 1))},
                      composite_push(camera, m.has_body, m.walk_chunk, p, m.walk_passes, m.long_count),
                      gpu::Elements(std::uint64_t(p == 0 ? tiles : m.long_count) * composite_workgroup(m.gpu_layout)));
  }
  {
    gpu::ScopedPass pass(stream, "splat/rasterize_project_bwd");
    stream.dispatch(ctx.kernel("splat/rasterize_project_bwd", {{0, 128}}),
                    {m.points, m.proj->range(0, segments * kProjected), m.grad_proj->range(0, segments * kProjected),
                     m.grad_segment->range(0, segments * 6), grad_confidence},
                    project_push(shape, camera, m.params), gpu::Elements(segments));
  }
  {
    gpu::ScopedPass pass(stream, "splat/rasterize_gather");
    const GatherPush gp{shape.strands, shape.points_per_strand, accumulate ? 1u : 0u};
    stream.dispatch(ctx.kernel("splat/rasterize_gather", {{0, 128}}), {m.grad_segment->range(0, segments * 6), grad_points}, gp,
                    gpu::Elements(shape.points()));
  }
}

namespace {

struct Uploaded {
  gpu::Buffer<float> points, confidence;
  std::unique_ptr<gpu::Buffer<float>> body;
  gpu::Buffer<float> image;
};

Uploaded upload(gpu::Context& context, const StrandShape& shape, std::span<const float> points, std::span<const float> confidence,
                const RasterCamera& camera, const RasterParams& params, std::span<const float> body_depth) {
  validate(shape, params.gaussian, points.size());
  validate(camera);
  if (confidence.size() != shape.segments())
    throw InputError("segment confidence: " + std::to_string(confidence.size()) + " values for " + std::to_string(shape.segments()) +
                     " segments");
  const std::uint64_t pixels = std::uint64_t(camera.width) * camera.height;
  if (!body_depth.empty() && body_depth.size() != pixels)
    throw InputError("body depth map: " + std::to_string(body_depth.size()) + " values for " + std::to_string(pixels) + " pixels");
  require_finite(points, "strand points");
  require_finite(confidence, "segment confidence");
  Uploaded u{gpu::Buffer<float>(context, std::max<std::size_t>(points.size(), 1), "strand points"),
             gpu::Buffer<float>(context, std::max<std::size_t>(confidence.size(), 1), "segment confidence"), nullptr,
             gpu::Buffer<float>(context, pixels * kChannels, "raster image")};
  if (!points.empty()) u.points.upload(points);
  if (!confidence.empty()) u.confidence.upload(confidence);
  if (!body_depth.empty()) u.body = std::make_unique<gpu::Buffer<float>>(context, body_depth, "body depth map");
  return u;
}

}  // namespace

std::vector<float> rasterize(gpu::Context& context, const StrandShape& shape, std::span<const float> points,
                             std::span<const float> confidence, const RasterCamera& camera, const RasterParams& params,
                             std::span<const float> body_depth) {
  Uploaded u = upload(context, shape, points, confidence, camera, params, body_depth);
  StrandRasterizer raster(context);
  raster.forward(shape, u.points, u.confidence, camera, params, u.body ? u.body->whole() : gpu::BufferRange{}, u.image);
  return u.image.download();
}

RasterGradients rasterize_backward(gpu::Context& context, const StrandShape& shape, std::span<const float> points,
                                   std::span<const float> confidence, const RasterCamera& camera,
                                   const RasterParams& params, std::span<const float> body_depth,
                                   std::span<const float> grad_image) {
  const std::uint64_t pixels = std::uint64_t(camera.width) * camera.height;
  if (grad_image.size() != pixels * kChannels) throw InputError("raster image gradient: size does not match the image");
  require_finite(grad_image, "raster image gradient");
  Uploaded u = upload(context, shape, points, confidence, camera, params, body_depth);
  StrandRasterizer raster(context);
  raster.forward(shape, u.points, u.confidence, camera, params, u.body ? u.body->whole() : gpu::BufferRange{}, u.image);
  gpu::Buffer<float> g_image(context, grad_image, "raster image gradient");
  gpu::Buffer<float> g_points(context, std::max<std::uint64_t>(shape.points() * 3, 1), "strand point gradients");
  gpu::Buffer<float> g_conf(context, std::max<std::uint64_t>(shape.segments(), 1), "segment confidence gradients");
  gpu::Stream stream(context);
  raster.backward(stream, g_image, g_points, g_conf, false);
  stream.submit_and_wait();
  return {g_points.download(0, shape.points() * 3), g_conf.download(0, shape.segments())};
}

}  // namespace nf::splat
