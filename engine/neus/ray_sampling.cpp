#include "engine/neus/ray_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/random.hpp"

namespace nf::neus {

namespace {

// Dilates a width x height binary mask by r pixels (square structuring element): two separable
// running-window passes.
std::vector<std::uint8_t> dilate_mask(const std::vector<std::uint8_t>& mask, std::uint32_t w, std::uint32_t h, int r) {
  std::vector<std::uint8_t> horiz(mask.size(), 0), out(mask.size(), 0);
  const long rr = r;
  for (std::uint32_t y = 0; y < h; ++y) {
    const std::uint8_t* row = mask.data() + std::size_t(y) * w;
    long in_window = 0;  // set pixels in [x - r, x + r]
    for (long x = 0; x < long(w) + rr; ++x) {
      if (x < long(w) && row[x]) ++in_window;
      const long centre = x - rr;
      if (centre >= 0) {
        horiz[std::size_t(y) * w + std::size_t(centre)] = in_window > 0;
        const long leaving = centre - rr;
        if (leaving >= 0 && row[leaving]) --in_window;
      }
    }
  }
  for (std::uint32_t x = 0; x < w; ++x) {
    long in_window = 0;
    for (long y = 0; y < long(h) + rr; ++y) {
      if (y < long(h) && horiz[std::size_t(y) * w + x]) ++in_window;
      const long centre = y - rr;
      if (centre >= 0) {
        out[std::size_t(centre) * w + x] = in_window > 0;
        const long leaving = centre - rr;
        if (leaving >= 0 && horiz[std::size_t(leaving) * w + x]) --in_window;
      }
    }
  }
  return out;
}

// Counter-based random stream: splitmix64 over (seed, ray, draw).
struct Rng : SplitMix64 {
  std::size_t index(std::size_t n) { return std::min(n - 1, std::size_t(uniform() * double(n))); }
};

Rng make_rng(unsigned seed, std::uint64_t ray) {
  Rng r{{std::uint64_t(seed) * 0xD1B54A32D192ED03ull ^ (ray + 1) * kGoldenGamma}};
  r.next();
  return r;
}

}  // namespace

std::size_t RayPool::count(RayClass c) const {
  std::size_t n = 0;
  for (const CameraPixels& cam : cameras) n += cam.pixels[std::size_t(c)].size();
  return n;
}

std::size_t RayPool::count(std::size_t camera, RayClass c) const { return cameras.at(camera).pixels[std::size_t(c)].size(); }

RayPool build_ray_pool(const io::Scene& scene, const std::vector<std::vector<std::uint8_t>>& masks,
                       const RayPoolOptions& options) {
  if (options.band_px < 0) throw InputError("ray pool: band_px must be >= 0, got " + std::to_string(options.band_px));
  if (!masks.empty() && masks.size() != scene.cameras.size())
    throw InputError("ray pool: " + std::to_string(masks.size()) + " masks for " + std::to_string(scene.cameras.size()) +
                     " cameras");
  RayPool pool;
  pool.cameras.resize(scene.cameras.size());
  for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
    const io::Camera& cam = scene.cameras[i];
    const std::uint64_t n = std::uint64_t(cam.width) * cam.height;
    if (n > std::numeric_limits<std::uint32_t>::max())
      throw InputError("ray pool: camera " + cam.name + " has too many pixels for 32-bit indices");
    auto& px = pool.cameras[i].pixels;
    if (masks.empty() || masks[i].empty()) {
      px[std::size_t(RayClass::inside)].resize(std::size_t(n));
      for (std::uint32_t p = 0; p < std::uint32_t(n); ++p) px[std::size_t(RayClass::inside)][p] = p;
      continue;
    }
    const std::vector<std::uint8_t>& mask = masks[i];
    if (mask.size() != n)
      throw InputError("ray pool: the mask of camera " + cam.name + " has " + std::to_string(mask.size()) +
                       " pixels, the camera " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
    const std::vector<std::uint8_t> grown = dilate_mask(mask, cam.width, cam.height, options.band_px);
    for (std::uint32_t p = 0; p < std::uint32_t(n); ++p) {
      const RayClass c = mask[p] ? RayClass::inside : grown[p] ? RayClass::band : RayClass::background;
      px[std::size_t(c)].push_back(p);
    }
    for (auto& v : px) v.shrink_to_fit();
  }
  return pool;
}

namespace {

// The ray's part inside the unit sphere, near clamped to >= near_epsilon; false when missed.
bool sphere_interval(const glm::dvec3& o, const glm::dvec3& d, double near_epsilon, double& t0, double& t1) {
  // |o + t d|^2 = 1 with |d| = 1.
  const double b = glm::dot(o, d), c = glm::dot(o, o) - 1.0, disc = b * b - c;
  if (!(disc > 0.0)) return false;
  const double s = std::sqrt(disc);
  t0 = std::max(-b - s, near_epsilon), t1 = -b + s;
  return t1 > t0;
}

// Amanatides-Woo through the grid (world box mapped to unit coordinates) over [t0, t1]: calls
// visit(enter, exit) for every occupied cell crossed, in order.
template <class Visit>
void walk_occupied_cells(const glm::dvec3& o, const glm::dvec3& d, const Normalisation& norm, const OccupancyGrid& grid,
                         double t0, double t1, Visit&& visit) {
  if (grid.dims.x <= 0 || grid.dims.y <= 0 || grid.dims.z <= 0) return;
  const glm::dvec3 lo = norm.to_unit(grid.lo), cs = grid.cell_size() * norm.scale;
  const glm::dvec3 hi = lo + cs * glm::dvec3(grid.dims);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {  // slabs
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  if (!(t1 > t0)) return;
  const glm::dvec3 g = (o + t0 * d - lo) / cs;
  glm::ivec3 cell, step;
  glm::dvec3 t_max, t_delta;
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(int(std::floor(g[a])), 0, grid.dims[a] - 1);
    if (d[a] > 0.0) {
      step[a] = 1, t_delta[a] = cs[a] / d[a], t_max[a] = (lo[a] + (cell[a] + 1) * cs[a] - o[a]) / d[a];
    } else if (d[a] < 0.0) {
      step[a] = -1, t_delta[a] = -cs[a] / d[a], t_max[a] = (lo[a] + cell[a] * cs[a] - o[a]) / d[a];
    } else {
      step[a] = 0, t_delta[a] = kInf, t_max[a] = kInf;
    }
  }
  double t = t0;
  while (t < t1) {
    const int a = t_max.x <= t_max.y ? (t_max.x <= t_max.z ? 0 : 2) : (t_max.y <= t_max.z ? 1 : 2);
    const double exit = std::min(t_max[a], t1);
    if (grid.at(cell.x, cell.y, cell.z) && exit > t) visit(t, exit);
    t = std::max(t, exit);
    cell[a] += step[a];
    if (cell[a] < 0 || cell[a] >= grid.dims[a]) break;
    t_max[a] += t_delta[a];
  }
}

}  // namespace

bool ray_interval(const glm::dvec3& o, const glm::dvec3& d, const Normalisation& norm, const OccupancyGrid* hull,
                  double near_epsilon, double& near_t, double& far_t) {
  near_t = far_t = 0.0;
  double t0 = 0.0, t1 = 0.0;
  if (!sphere_interval(o, d, near_epsilon, t0, t1)) return false;
  if (hull == nullptr) {
    near_t = t0, far_t = t1;
    return true;
  }
  double first = -1.0, last = -1.0;
  walk_occupied_cells(o, d, norm, *hull, t0, t1, [&](double enter, double exit) {
    if (first < 0.0) first = enter;
    last = exit;
  });
  if (first < 0.0 || !(last > first)) return false;
  near_t = first, far_t = last;
  return true;
}

std::vector<Segment> occupied_segments(const glm::dvec3& o, const glm::dvec3& d, const Normalisation& norm,
                                       const OccupancyGrid& grid, double near_epsilon) {
  std::vector<Segment> segments;
  double t0 = 0.0, t1 = 0.0, last_exit = -1.0;
  if (!sphere_interval(o, d, near_epsilon, t0, t1)) return segments;
  walk_occupied_cells(o, d, norm, grid, t0, t1, [&](double enter, double exit) {
    if (!segments.empty() && enter <= last_exit + 1e-9)
      segments.back().far = float(exit);  // cells in a row make one segment
    else
      segments.push_back({float(enter), float(exit)});
    last_exit = exit;
  });
  return segments;
}

void stratified_samples(const std::vector<Segment>& segments, std::uint32_t count, float jitter,
                        std::vector<float>& t, std::vector<float>& dist) {
  t.clear();
  dist.clear();
  double total = 0.0;
  for (const Segment& s : segments) total += double(s.far) - double(s.near);
  if (count == 0 || !(total > 0.0)) return;
  const double step = total / count;
  std::size_t seg = 0;
  double before = 0.0;  // length of the segments before `seg`
  for (std::uint32_t j = 0; j < count; ++j) {
    const double u = (j + double(jitter)) * step;
    while (seg + 1 < segments.size() && u >= before + (double(segments[seg].far) - double(segments[seg].near))) {
      before += double(segments[seg].far) - double(segments[seg].near);
      ++seg;
    }
    t.push_back(float(double(segments[seg].near) + (u - before)));
    dist.push_back(float(step));
  }
}

std::vector<Ray> sample_rays(const RayPool& pool, const io::Scene& scene, const Normalisation& norm,
                             const OccupancyGrid* hull, std::uint32_t count, unsigned seed,
                             const RaySampleOptions& options) {
  if (pool.cameras.size() != scene.cameras.size())
    throw InputError("sample_rays: the ray pool has " + std::to_string(pool.cameras.size()) + " cameras, the scene " +
                     std::to_string(scene.cameras.size()));
  const double share[kRayClassCount] = {options.inside_share, options.band_share, options.background_share};
  double total_share = 0.0;
  std::size_t class_pixels[kRayClassCount];
  for (int c = 0; c < kRayClassCount; ++c) {
    if (!(share[c] >= 0.0) || !std::isfinite(share[c]))
      throw InputError("sample_rays: class shares must be finite and >= 0");
    class_pixels[c] = pool.count(RayClass(c));
    if (class_pixels[c] > 0) total_share += share[c];
  }
  std::vector<Ray> rays;
  if (count == 0) return rays;
  if (!(total_share > 0.0)) throw InputError("sample_rays: no class with pixels has a share > 0");

  // Class counts by largest remainder.
  std::uint32_t n[kRayClassCount] = {0, 0, 0};
  double rem[kRayClassCount] = {-1.0, -1.0, -1.0};
  std::uint32_t assigned = 0;
  for (int c = 0; c < kRayClassCount; ++c) {
    if (class_pixels[c] == 0) continue;
    const double exact = double(count) * share[c] / total_share;
    n[c] = std::uint32_t(std::floor(exact));
    rem[c] = share[c] > 0.0 ? exact - n[c] : -1.0;
    assigned += n[c];
  }
  while (assigned < count) {
    const int c = int(std::max_element(rem, rem + kRayClassCount) - rem);
    ++n[c], ++assigned, rem[c] = -1.0;
  }

  // Per class, the prefix sum of pixel counts over cameras.
  std::vector<std::size_t> offsets[kRayClassCount];
  for (int c = 0; c < kRayClassCount; ++c) {
    offsets[c].resize(pool.cameras.size() + 1, 0);
    for (std::size_t i = 0; i < pool.cameras.size(); ++i)
      offsets[c][i + 1] = offsets[c][i] + pool.cameras[i].pixels[std::size_t(c)].size();
  }
  const double eps = options.near_epsilon;
  const int max_draws = std::max(1, options.max_redraws);

  rays.reserve(count);
  std::uint64_t ray_index = 0;
  for (int c = 0; c < kRayClassCount; ++c) {
    for (std::uint32_t k = 0; k < n[c]; ++k, ++ray_index) {
      Rng rng = make_rng(seed, ray_index);
      Ray ray;
      for (int draw = 0; draw < max_draws; ++draw) {
        const std::size_t flat = rng.index(class_pixels[c]);
        const std::size_t cam_i =
            std::size_t(std::upper_bound(offsets[c].begin(), offsets[c].end(), flat) - offsets[c].begin()) - 1;
        const io::Camera& cam = scene.cameras[cam_i];
        const std::uint32_t pixel = pool.cameras[cam_i].pixels[std::size_t(c)][flat - offsets[c][cam_i]];
        const double jx = options.jitter ? rng.uniform() : 0.5, jy = options.jitter ? rng.uniform() : 0.5;
        const double px = double(pixel % cam.width) + jx, py = double(pixel / cam.width) + jy;
        const glm::dvec3 dir_cam((px - cam.cx) / cam.fx, -(py - cam.cy) / cam.fy, -1.0);
        const glm::dvec3 d = glm::normalize(glm::dmat3(cam.camera_to_world) * dir_cam);
        const glm::dvec3 o = norm.to_unit(glm::dvec3(cam.camera_to_world[3]));
        double t_near = 0.0, t_far = 0.0;
        const bool hit = ray_interval(o, d, norm, hull, eps, t_near, t_far);
        ray.origin = glm::vec3(o), ray.direction = glm::vec3(d);
        ray.near = float(t_near), ray.far = float(t_far);
        if (hit && !(ray.near < ray.far)) ray.far = std::nextafter(ray.near, std::numeric_limits<float>::infinity());
        ray.camera = std::uint32_t(cam_i), ray.pixel = pixel;
        ray.cls = std::uint8_t(hit ? c : int(RayClass::background));
        if (hit || c == int(RayClass::background)) break;
      }
      rays.push_back(ray);
    }
  }
  return rays;
}

std::vector<float> upsample_positions(const std::vector<float>& t, const std::vector<float>& sdf, float max_gap,
                                      float inv_s, std::uint32_t count, float jitter) {
  std::vector<float> out;
  const std::size_t n = t.size();
  if (count == 0 || n < 2 || sdf.size() != n) return out;
  const auto sigmoid = [](double x) { return x >= 0 ? 1.0 / (1.0 + std::exp(-x)) : std::exp(x) / (1.0 + std::exp(x)); };
  std::vector<double> weight(n - 1, 0.0);
  double transmittance = 1.0, previous_cos = 0.0, total = 0.0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double dist = double(t[i + 1]) - double(t[i]);
    if (!(dist > 0.0) || dist > max_gap || !std::isfinite(sdf[i]) || !std::isfinite(sdf[i + 1])) {
      previous_cos = 0.0;
      continue;
    }
    const double mid = 0.5 * (double(sdf[i]) + double(sdf[i + 1]));
    double cos = (double(sdf[i + 1]) - double(sdf[i])) / (dist + 1e-5);
    cos = std::clamp(std::min(cos, previous_cos), -1e3, 0.0);
    previous_cos = (double(sdf[i + 1]) - double(sdf[i])) / (dist + 1e-5);
    const double prev = mid - cos * dist * 0.5, next = mid + cos * dist * 0.5;
    const double p = sigmoid(prev * inv_s), c = sigmoid(next * inv_s);
    const double alpha = std::clamp((p - c + 1e-5) / (p + 1e-5), 0.0, 1.0);
    weight[i] = alpha * transmittance + 1e-5 * dist;  // a floor keeps every occupied interval reachable
    transmittance *= 1.0 - alpha + 1e-7;
    total += weight[i];
  }
  if (!(total > 0.0)) return out;
  out.reserve(count);
  std::size_t i = 0;
  double before = 0.0;  // cumulative weight before interval i
  for (std::uint32_t j = 0; j < count; ++j) {
    const double u = (j + double(jitter)) / count * total;
    while (i + 2 < n && before + weight[i] <= u) before += weight[i++];
    const double f = weight[i] > 0.0 ? std::clamp((u - before) / weight[i], 0.0, 1.0) : 0.5;
    out.push_back(float(double(t[i]) + f * (double(t[i + 1]) - double(t[i]))));
  }
  return out;
}

void merge_samples(const std::vector<float>& a, const std::vector<float>& b, float max_section, std::vector<float>& t,
                   std::vector<float>& dist) {
  t.resize(a.size() + b.size());
  std::merge(a.begin(), a.end(), b.begin(), b.end(), t.begin());
  dist.assign(t.size(), 0.f);
  for (std::size_t k = 0; k < t.size(); ++k) {
    const float before = k > 0 ? std::min(0.5f * (t[k] - t[k - 1]), 0.5f * max_section) : 0.5f * max_section;
    const float after = k + 1 < t.size() ? std::min(0.5f * (t[k + 1] - t[k]), 0.5f * max_section) : 0.5f * max_section;
    dist[k] = before + after;
  }
}

}  // namespace nf::neus
