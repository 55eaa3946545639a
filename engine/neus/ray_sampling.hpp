#pragma once
// Ray selection for the NeuS surface stage: rays only where they matter. Per camera the pixels are
// split once into three classes (inside the mask, a band of `band_px` pixels around it, background)
// and each training batch draws a fixed share of rays from each class. Rays live in the normalised
// (unit-sphere) coordinates of visual_hull.hpp's Normalisation; each carries its [near, far]
// interval: the unit sphere, tightened to the occupied cells of the visual hull when one is given.
//
// CPU code, deterministic for a given seed (ray i draws from its own counter-based random stream).
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/scene.hpp"
#include "engine/neus/visual_hull.hpp"

namespace nf::neus {

enum class RayClass : std::uint8_t { inside = 0, band = 1, background = 2 };
constexpr int kRayClassCount = 3;

struct RayPoolOptions {
  int band_px = 4;  // band = mask dilated by this many pixels (square structuring element) minus the mask
};

// Per camera, the pixel indices (y * width + x, ascending) of each class. Built once per scene.
struct RayPool {
  struct CameraPixels {
    std::array<std::vector<std::uint32_t>, kRayClassCount> pixels;  // indexed by RayClass
  };
  std::vector<CameraPixels> cameras;  // one per scene camera
  std::size_t count(RayClass c) const;                    // over all cameras
  std::size_t count(std::size_t camera, RayClass c) const;
};

// masks: one per camera (or none at all), width * height bytes, row-major, y down; nonzero = the
// animal. A camera whose mask is empty puts every pixel in "inside" (no band, no background). An
// all-zero mask gives an empty inside class and an empty band: that view contributes background
// rays only. InputError when the mask count or a mask's size does not match the cameras, or
// band_px < 0.
RayPool build_ray_pool(const io::Scene& scene, const std::vector<std::vector<std::uint8_t>>& masks,
                       const RayPoolOptions& options = {});

// A ray in unit-sphere coordinates: points are origin + t * direction, t in [near, far]
// (direction has unit length, so t is a distance in unit coordinates). near >= far flags a ray
// that misses (see sample_rays); such rays are always of class background.
struct Ray {
  glm::vec3 origin{0.f}, direction{0.f, 0.f, -1.f};
  float near = 0.f, far = 0.f;
  std::uint32_t camera = 0, pixel = 0;  // pixel = y * width + x
  std::uint8_t cls = 0;                 // a RayClass
  bool hit() const { return near < far; }
};

struct RaySampleOptions {
  float inside_share = 0.80f, band_share = 0.15f, background_share = 0.05f;  // >= 0, not all 0
  float near_epsilon = 1e-3f;  // smallest near (unit coordinates): cameras inside the unit sphere
  bool jitter = true;          // a uniform point of the pixel; false: the pixel centre
  int max_redraws = 32;        // inside/band draws per ray before giving up (see sample_rays)
};

// Draws `count` rays.
//  - Class counts: the shares of the classes with at least one pixel in the pool, renormalised to
//    sum 1 (empty classes get nothing), rounded by largest remainder so they sum to `count`
//    exactly. Within a class, pixels are uniform over all cameras' pixels of that class. Rays come
//    grouped by class (inside, band, background).
//  - near/far: the ray's interval inside the unit sphere, near clamped to >= near_epsilon (a camera
//    inside the sphere gets near = near_epsilon). With `hull`, the interval is tightened to
//    [entry of the first, exit of the last] occupied cell the ray crosses (3D DDA in unit
//    coordinates; the grid keeps its world box, mapped through `norm`), near still >= near_epsilon.
//  - Missed rays (the sphere is missed or behind the camera, or no occupied cell is crossed) get
//    near = far = 0 (near >= far). They are kept only in the background class, where they stand for
//    empty space (expected opacity 0, nothing to sample). An inside or band draw that misses is
//    redrawn (another pixel of the class), up to max_redraws times; if all miss, the last draw is
//    kept as a missed ray and relabelled background, so `count` is always met.
// InputError when the shares are negative or all 0, or the pool does not match the scene.
std::vector<Ray> sample_rays(const RayPool& pool, const io::Scene& scene, const Normalisation& norm,
                             const OccupancyGrid* hull, std::uint32_t count, unsigned seed,
                             const RaySampleOptions& options = {});

// The [near, far] rule above for one ray (unit coordinates, unit-length direction); returns false
// (and near = far = 0) on a miss. Exposed for tests and for the GPU sampler to match.
bool ray_interval(const glm::dvec3& origin, const glm::dvec3& direction, const Normalisation& norm,
                  const OccupancyGrid* hull, double near_epsilon, double& near, double& far);

// A stretch [near, far] of a ray (unit coordinates) through occupied cells.
struct Segment {
  float near = 0.f, far = 0.f;
};

// The ray's stretches inside the unit sphere (near >= near_epsilon) through occupied cells of
// `grid` (world box, mapped through `norm`), adjacent cells merged, in order along the ray.
std::vector<Segment> occupied_segments(const glm::dvec3& origin, const glm::dvec3& direction, const Normalisation& norm,
                                       const OccupancyGrid& grid, double near_epsilon);

// `count` stratified samples over the segments as if laid end to end: sample j at
// (j + jitter) / count of the total length, jitter in [0, 1). Each sample stands for an interval
// of length total / count (`dist`); gaps between segments are empty space and get no samples.
// Empty outputs when the segments have no length.
void stratified_samples(const std::vector<Segment>& segments, std::uint32_t count, float jitter,
                        std::vector<float>& t, std::vector<float>& dist);

// NeuS up-sampling (the official code's up_sample, one round): from a ray's coarse positions t
// (ascending) and the SDF there, the NeuS weights at inverse variance inv_s (interval cosines from
// SDF differences, min with the previous interval's, clipped to [-1e3, 0]) are sampled by inverse
// CDF at `count` stratified points ((j + jitter) / count). Intervals longer than max_gap span a gap
// between occupied segments and get no weight. Returns ascending positions (empty when count is 0
// or fewer than two coarse samples).
std::vector<float> upsample_positions(const std::vector<float>& t, const std::vector<float>& sdf, float max_gap,
                                      float inv_s, std::uint32_t count, float jitter);

// The sorted union of two position sets, each sample's section being half-way to its neighbours
// (so sections tile the sampled stretches), capped at max_section (gaps are empty space); the end
// samples extend half of max_section outwards.
void merge_samples(const std::vector<float>& a, const std::vector<float>& b, float max_section, std::vector<float>& t,
                   std::vector<float>& dist);

}  // namespace nf::neus
