#include "engine/neus/visual_hull.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/image.hpp"

namespace nf::neus {

namespace {

// One masked camera, ready for the carve: world-to-camera transform, intrinsics and the summed-area
// table of its dilated mask ((w + 1) x (h + 1), row 0 and column 0 zero).
struct View {
  std::size_t camera = 0;
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  glm::dmat4 world_to_camera{1.0};
  std::vector<std::uint32_t> sat;
  std::uint64_t set_pixels = 0;
  // The mask touches no image border: the whole object is in view, so cells projecting outside the
  // image (or lying behind the camera) are outside the object. Otherwise a partial view.
  bool full_view = true;

  std::uint32_t sat_at(int x, int y) const { return sat[std::size_t(y) * std::size_t(width + 1) + std::size_t(x)]; }
  // Set pixels in columns [x0, x1], rows [y0, y1] (inclusive, inside the image).
  std::uint32_t count(int x0, int y0, int x1, int y1) const {
    return sat_at(x1 + 1, y1 + 1) - sat_at(x0, y1 + 1) - sat_at(x1 + 1, y0) + sat_at(x0, y0);
  }
};

// Square (Chebyshev) dilation by r pixels, separable.
std::vector<std::uint8_t> dilate_mask(const std::vector<std::uint8_t>& m, int w, int h, int r) {
  if (r <= 0) return m;
  std::vector<std::uint8_t> tmp(m.size(), 0), out(m.size(), 0);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = &m[std::size_t(y) * std::size_t(w)];
    for (int x = 0; x < w; ++x) {
      std::uint8_t v = 0;
      for (int d = -r; d <= r && !v; ++d) {
        const int xx = x + d;
        if (xx >= 0 && xx < w) v = row[xx];
      }
      tmp[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
    }
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t v = 0;
      for (int d = -r; d <= r && !v; ++d) {
        const int yy = y + d;
        if (yy >= 0 && yy < h) v = tmp[std::size_t(yy) * std::size_t(w) + std::size_t(x)];
      }
      out[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
    }
  return out;
}

enum class Verdict { Unseen, Carved, Kept };

struct CellTest {
  const std::vector<View>& views;
  glm::dvec3 lo, cell;
  int min_views;

  // What one camera says about cell (i, j, k): carved, and whether its centre is seen.
  bool carves(const View& v, const glm::dvec3& corner0, bool& seen) const {
    const glm::dmat4& m = v.world_to_camera;
    const glm::dvec3 base = glm::dvec3(m * glm::dvec4(corner0, 1.0));
    const glm::dvec3 ex = glm::dmat3(m)[0] * cell.x, ey = glm::dmat3(m)[1] * cell.y, ez = glm::dmat3(m)[2] * cell.z;
    const glm::dvec3 centre = base + 0.5 * (ex + ey + ez);
    if (-centre.z > 0) {
      const double u = v.cx + v.fx * centre.x / -centre.z, w = v.cy - v.fy * centre.y / -centre.z;
      seen = u >= 0 && w >= 0 && u < v.width && w < v.height;
    } else {
      seen = false;
    }
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    int behind = 0;
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 p = base + ((c & 1) ? ex : glm::dvec3(0.0)) + ((c & 2) ? ey : glm::dvec3(0.0)) +
                           ((c & 4) ? ez : glm::dvec3(0.0));
      const double depth = -p.z;
      if (!(depth > 0)) {
        ++behind;
        continue;
      }
      const double u = v.cx + v.fx * p.x / depth, w = v.cy - v.fy * p.y / depth;
      xmin = std::min(xmin, u), xmax = std::max(xmax, u);
      ymin = std::min(ymin, w), ymax = std::max(ymax, w);
    }
    // Wholly behind the camera: outside a full view; a partial view says nothing. Straddling the
    // camera plane: the projection is unbounded, keep.
    if (behind == 8) return v.full_view;
    if (behind > 0) return false;
    const bool inside_image = xmin >= 0 && ymin >= 0 && xmax < v.width && ymax < v.height;
    // Partly outside a partial view's image: the mask says nothing about that part.
    if (!inside_image && !v.full_view) return false;
    const double x0 = std::max(0.0, std::floor(xmin)), y0 = std::max(0.0, std::floor(ymin));
    const double x1 = std::min(double(v.width - 1), std::floor(xmax)), y1 = std::min(double(v.height - 1), std::floor(ymax));
    if (x0 > x1 || y0 > y1) return true;  // wholly outside a full view's image
    return v.count(int(x0), int(y0), int(x1), int(y1)) == 0;
  }
};

// One carve of the box [lo, lo + dims * cell] (cubic cells). Fast path: a cell stops at the first
// camera that carves it.
std::vector<std::uint8_t> carve(const std::vector<View>& views, glm::dvec3 lo, glm::dvec3 cell, glm::ivec3 dims,
                                int min_views) {
  std::vector<std::uint8_t> occ(std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z), 0);
  const CellTest test{views, lo, cell, min_views};
  for_each_dynamic(dims.z, [&](int k) {
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const glm::dvec3 corner0 = lo + glm::dvec3(i, j, k) * cell;
        int seen = 0;
        bool carved = false;
        for (const View& v : views) {
          bool s = false;
          if (test.carves(v, corner0, s)) {
            carved = true;
            break;
          }
          seen += s;
        }
        if (!carved && seen >= min_views)
          occ[(std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) + std::size_t(i)] = 1;
      }
  });
  return occ;
}

// The hull came out empty: find out why and say so, naming the camera when one is to blame.
[[noreturn]] void explain_empty(const io::Scene& scene, const std::string& source, const std::vector<View>& views,
                                glm::dvec3 lo, glm::dvec3 cell, glm::ivec3 dims, int min_views) {
  const CellTest test{views, lo, cell, min_views};
  std::vector<std::uint64_t> sole(views.size(), 0), total(views.size(), 0);
  std::uint64_t seen_cells = 0;
  std::mutex mutex;
  for_each_dynamic(dims.z, [&](int k) {
    std::vector<std::uint64_t> s(views.size(), 0), t(views.size(), 0);
    std::uint64_t sc = 0;
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const glm::dvec3 corner0 = lo + glm::dvec3(i, j, k) * cell;
        int seen = 0, carvers = 0;
        std::size_t last = 0;
        for (std::size_t vi = 0; vi < views.size(); ++vi) {
          bool sv = false;
          if (test.carves(views[vi], corner0, sv)) ++carvers, last = vi, ++t[vi];
          seen += sv;
        }
        if (seen < min_views) continue;
        ++sc;
        if (carvers == 1) ++s[last];
      }
    std::lock_guard<std::mutex> lock(mutex);
    for (std::size_t vi = 0; vi < views.size(); ++vi) sole[vi] += s[vi], total[vi] += t[vi];
    seen_cells += sc;
  });
  const auto describe = [&](std::size_t vi) {
    const io::Camera& c = scene.cameras[views[vi].camera];
    return "camera '" + c.name + "' (mask " + c.mask.string() + ", " + std::to_string(views[vi].set_pixels) +
           " pixels set after dilation)";
  };
  if (seen_cells == 0)
    throw InputError(source + ": the visual hull is empty: no region is seen by " + std::to_string(min_views) +
                     " masked cameras; do the cameras look at a common object?");
  const std::size_t worst = std::size_t(std::max_element(sole.begin(), sole.end()) - sole.begin());
  if (sole[worst] > 0)
    throw InputError(source + ": the visual hull is empty: " + describe(worst) +
                     " carves away every region the other cameras keep; is its mask empty, inverted or for another "
                     "image, or its pose wrong?");
  const std::size_t most = std::size_t(std::max_element(total.begin(), total.end()) - total.begin());
  throw InputError(source + ": the visual hull is empty: the masks are inconsistent (no region projects inside all "
                   "of them); the camera that carves most is " + describe(most) + "; check the poses and masks");
}

// A camera cannot sit inside the animal: a cell around its centre that every other camera seeing
// it keeps (in its mask, in front of it) means a wrong pose (a world-to-camera matrix given as
// camera-to-world, a translation in other units) that the carve alone would silently accept.
void check_cameras_outside(const io::Scene& scene, const std::string& source, const std::vector<View>& views,
                           glm::dvec3 cell, int min_views) {
  const CellTest test{views, glm::dvec3(0.0), cell, min_views};
  for (std::size_t ci = 0; ci < scene.cameras.size(); ++ci) {
    const glm::dvec3 centre(scene.cameras[ci].camera_to_world[3]);
    int seen = 0;
    bool carved = false;
    for (const View& v : views) {
      if (v.camera == ci) continue;
      bool s = false;
      if (test.carves(v, centre - 0.5 * cell, s)) {
        carved = true;
        break;
      }
      seen += s;
    }
    if (carved || seen < std::max(2, min_views)) continue;
    // Its own mask covering the whole image agrees (a camera inside sees only the object): the carve
    // copes with that (the camera carves nothing). A mask of an outline does not: the data lie.
    const auto own = std::find_if(views.begin(), views.end(), [&](const View& v) { return v.camera == ci; });
    const std::string where = source + ": camera '" + scene.cameras[ci].name + "' sits inside the animal: its position lies in the masks of all " +
                              std::to_string(seen) + " other cameras that see it";
    if (own != views.end() && own->set_pixels == std::uint64_t(own->width) * std::uint64_t(own->height)) {
      log::warn(where, "; its own mask covers its whole image, so it is kept, but check its pose");
      continue;
    }
    throw InputError(where + ". Its pose is wrong (the transform is camera-to-world, OpenGL axes: x right, y up, looking down " +
                     "-z; translations in the scene's units) or the masks belong to other photos");
  }
}

double longest(const glm::dvec3& e) { return std::max({e.x, e.y, e.z}); }

// A grid of cubic cells covering [box_lo, box_hi] with `resolution` cells along its longest axis,
// centred on the box.
void grid_for(glm::dvec3 box_lo, glm::dvec3 box_hi, int resolution, glm::dvec3& lo, glm::dvec3& cell, glm::ivec3& dims) {
  const glm::dvec3 extent = box_hi - box_lo;
  const double size = longest(extent) / resolution;
  for (int a = 0; a < 3; ++a) dims[a] = std::max(1, int(std::ceil(extent[a] / size - 1e-9)));
  cell = glm::dvec3(size);
  lo = 0.5 * (box_lo + box_hi) - 0.5 * glm::dvec3(dims) * size;
}

void bounds_of(const std::vector<std::uint8_t>& occ, glm::ivec3 dims, glm::ivec3& a, glm::ivec3& b) {
  a = dims, b = glm::ivec3(-1);
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i)
        if (occ[(std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) + std::size_t(i)]) {
          a = glm::min(a, glm::ivec3(i, j, k));
          b = glm::max(b, glm::ivec3(i, j, k));
        }
}

bool any_set(const std::vector<std::uint8_t>& v) { return std::find(v.begin(), v.end(), 1) != v.end(); }

}  // namespace

bool OccupancyGrid::cell_of(const glm::dvec3& p, glm::ivec3& cell) const {
  const glm::dvec3 f = (p - lo) / cell_size();
  for (int a = 0; a < 3; ++a) {
    if (!(f[a] >= 0.0 && f[a] < double(dims[a]))) return false;
    cell[a] = std::min(dims[a] - 1, int(f[a]));
  }
  return true;
}

bool OccupancyGrid::contains(const glm::dvec3& p) const {
  glm::ivec3 c;
  return cell_of(p, c) && at(c.x, c.y, c.z);
}

std::size_t OccupancyGrid::occupied_count() const {
  return std::size_t(std::count_if(occupied.begin(), occupied.end(), [](std::uint8_t v) { return v != 0; }));
}

double OccupancyGrid::occupied_fraction() const {
  return occupied.empty() ? 0.0 : double(occupied_count()) / double(occupied.size());
}

double OccupancyGrid::occupied_volume() const {
  const glm::dvec3 c = cell_size();
  return double(occupied_count()) * c.x * c.y * c.z;
}

void OccupancyGrid::occupied_bounds(glm::dvec3& box_lo, glm::dvec3& box_hi) const {
  glm::ivec3 a, b;
  bounds_of(occupied, dims, a, b);
  NF_CHECK(b.x >= 0, "occupied_bounds of an empty occupancy grid");
  box_lo = lo + glm::dvec3(a) * cell_size();
  box_hi = lo + glm::dvec3(b + 1) * cell_size();
}

OccupancyGrid carve_visual_hull(const io::Scene& scene, const VisualHullOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string source = scene.root.empty() ? std::string("scene") : scene.root.string();
  if (options.resolution < 2 || options.resolution > 2048)
    throw UsageError("visual hull: resolution must be in [2, 2048], got " + std::to_string(options.resolution));
  if (options.coarse_resolution < 2 || options.coarse_resolution > 2048)
    throw UsageError("visual hull: coarse_resolution must be in [2, 2048], got " +
                     std::to_string(options.coarse_resolution));
  if (options.dilate_px < 0 || options.dilate_px > 1000)
    throw UsageError("visual hull: dilate_px must be in [0, 1000], got " + std::to_string(options.dilate_px));
  if (options.min_views < 1) throw UsageError("visual hull: min_views must be >= 1");
  if (options.margin_cells < 0) throw UsageError("visual hull: margin_cells must be >= 0");

  // Masks -> dilated summed-area tables, read in parallel.
  std::vector<std::size_t> masked;
  for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
    if (scene.cameras[c].mask.empty())
      log::warn(source, ": camera '", scene.cameras[c].name, "' has no mask; the visual hull ignores it");
    else
      masked.push_back(c);
  }
  if (masked.empty())
    throw InputError(source + ": no camera has a mask; the visual hull (and the NeuS stage) needs masks "
                              "(mask_path per frame in transforms.json)");
  std::vector<View> views(masked.size());
  for_each_dynamic(int(masked.size()), [&](int vi) {
    const io::Camera& cam = scene.cameras[masked[std::size_t(vi)]];
    const io::Image image = io::read_image(cam.mask);
    if (image.width != cam.width || image.height != cam.height)
      throw InputError(source + ": camera '" + cam.name + "': mask " + cam.mask.string() + " is " +
                       std::to_string(image.width) + "x" + std::to_string(image.height) + ", the camera is " +
                       std::to_string(cam.width) + "x" + std::to_string(cam.height));
    View& v = views[std::size_t(vi)];
    v.camera = masked[std::size_t(vi)];
    v.width = int(cam.width), v.height = int(cam.height);
    v.fx = cam.fx, v.fy = cam.fy, v.cx = cam.cx, v.cy = cam.cy;
    v.world_to_camera = glm::inverse(cam.camera_to_world);
    const std::vector<std::uint8_t> raw = io::mask_of(image);
    for (int x = 0; x < v.width && v.full_view; ++x)
      v.full_view = !raw[std::size_t(x)] && !raw[std::size_t(v.height - 1) * std::size_t(v.width) + std::size_t(x)];
    for (int y = 0; y < v.height && v.full_view; ++y)
      v.full_view = !raw[std::size_t(y) * std::size_t(v.width)] && !raw[std::size_t(y) * std::size_t(v.width) + std::size_t(v.width - 1)];
    // An empty mask says only that nothing lies in this camera's view, not that the animal is in
    // it: it carves what it sees (a partial view), never what lies outside its image.
    if (std::none_of(raw.begin(), raw.end(), [](std::uint8_t m) { return m != 0; })) v.full_view = false;
    const std::vector<std::uint8_t> m = dilate_mask(raw, v.width, v.height, options.dilate_px);
    v.sat.assign(std::size_t(v.width + 1) * std::size_t(v.height + 1), 0);
    for (int y = 0; y < v.height; ++y) {
      std::uint32_t row = 0;
      for (int x = 0; x < v.width; ++x) {
        row += m[std::size_t(y) * std::size_t(v.width) + std::size_t(x)];
        v.sat[std::size_t(y + 1) * std::size_t(v.width + 1) + std::size_t(x + 1)] =
            v.sat[std::size_t(y) * std::size_t(v.width + 1) + std::size_t(x + 1)] + row;
      }
    }
    v.set_pixels = v.sat.back();
  });
  if (std::all_of(views.begin(), views.end(), [](const View& v) { return v.set_pixels == 0; }))
    throw InputError(source + ": every mask is empty (" + scene.cameras[views[0].camera].mask.parent_path().string() +
                     "/ and the others): nothing marks the animal. A mask is white (or opaque alpha) on the animal and "
                     "black elsewhere; check that the masks are not inverted, blank or written with another bit depth");
  const int min_views = std::min(options.min_views, int(views.size()));
  const auto partial = std::count_if(views.begin(), views.end(), [](const View& v) { return !v.full_view; });
  if (partial > 0)
    log::info(source, ": ", partial, " of ", views.size(),
              " masks touch the image border (partial views): they carve only inside their images");

  // Start box: the least-squares closest point to all optical axes, +- the mean camera distance.
  glm::dmat3 a(0.0);
  glm::dvec3 b(0.0);
  for (const View& v : views) {
    const glm::dmat4& c2w = scene.cameras[v.camera].camera_to_world;
    const glm::dvec3 o(c2w[3]), d = glm::normalize(-glm::dvec3(c2w[2]));
    const glm::dmat3 p = glm::dmat3(1.0) - glm::outerProduct(d, d);
    a += p, b += p * o;
  }
  // The normal matrix is a sum of projectors: its eigenvalues lie in [0, n]. Nearly parallel axes
  // give a tiny determinant relative to the trace's scale.
  const double tr = a[0][0] + a[1][1] + a[2][2];
  if (!(std::abs(glm::determinant(a)) > 1e-6 * tr * tr * tr))
    throw InputError(source + ": the masked cameras' optical axes are (nearly) parallel; the visual hull needs "
                              "cameras that look at the object from different directions");
  const glm::dvec3 look_at = glm::inverse(a) * b;
  double distance = 0;
  for (const View& v : views) distance += glm::length(glm::dvec3(scene.cameras[v.camera].camera_to_world[3]) - look_at);
  distance /= double(views.size());
  if (!(distance > 0) || !std::isfinite(distance))
    throw InputError(source + ": the cameras do not surround a point at a finite distance");
  glm::dvec3 box_lo = look_at - distance, box_hi = look_at + distance;

  glm::dvec3 lo, cell;
  glm::ivec3 dims;
  for (int round = 0; round < 4; ++round) {
    grid_for(box_lo, box_hi, options.coarse_resolution, lo, cell, dims);
    const std::vector<std::uint8_t> occ = carve(views, lo, cell, dims, min_views);
    if (!any_set(occ)) explain_empty(scene, source, views, lo, cell, dims, min_views);
    glm::ivec3 ia, ib;
    bounds_of(occ, dims, ia, ib);
    const glm::dvec3 new_lo = lo + (glm::dvec3(ia) - double(options.margin_cells)) * cell;
    const glm::dvec3 new_hi = lo + (glm::dvec3(ib + 1) + double(options.margin_cells)) * cell;
    const bool shrank_a_lot = longest(new_hi - new_lo) < 0.5 * longest(box_hi - box_lo);
    box_lo = new_lo, box_hi = new_hi;
    if (!shrank_a_lot) break;
  }

  grid_for(box_lo, box_hi, options.resolution, lo, cell, dims);
  OccupancyGrid grid;
  grid.lo = lo, grid.dims = dims, grid.hi = lo + glm::dvec3(dims) * cell;
  grid.occupied = carve(views, lo, cell, dims, min_views);
  if (!any_set(grid.occupied)) explain_empty(scene, source, views, lo, cell, dims, min_views);
  check_cameras_outside(scene, source, views, cell, min_views);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  log::info(source, ": visual hull from ", views.size(), " masks: ", dims.x, "x", dims.y, "x", dims.z, " cells, ",
            100.0 * grid.occupied_fraction(), "% occupied, ", seconds, " s");
  return grid;
}

OccupancyGrid dilate(const OccupancyGrid& grid, int cells) {
  if (cells < 0) throw UsageError("dilate: cells must be >= 0, got " + std::to_string(cells));
  OccupancyGrid out;
  const glm::dvec3 cs = grid.cell_size();
  out.dims = grid.dims + 2 * cells;
  out.lo = grid.lo - double(cells) * cs;
  out.hi = grid.hi + double(cells) * cs;
  out.occupied.assign(out.cell_count(), 0);
  for (int k = 0; k < grid.dims.z; ++k)
    for (int j = 0; j < grid.dims.y; ++j)
      for (int i = 0; i < grid.dims.x; ++i)
        out.occupied[out.index(i + cells, j + cells, k + cells)] = grid.occupied[grid.index(i, j, k)];
  if (cells == 0) return out;
  // Separable max along x, y, z.
  std::vector<std::uint8_t> tmp(out.occupied.size());
  const glm::ivec3 d = out.dims;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t stride = axis == 0 ? 1 : axis == 1 ? std::size_t(d.x) : std::size_t(d.x) * std::size_t(d.y);
    for (int k = 0; k < d.z; ++k)
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i) {
          const int pos = axis == 0 ? i : axis == 1 ? j : k;
          const std::size_t idx = out.index(i, j, k);
          std::uint8_t v = 0;
          for (int s = std::max(0, pos - cells); s <= std::min(d[axis] - 1, pos + cells) && !v; ++s)
            v = out.occupied[idx - std::size_t(pos) * stride + std::size_t(s) * stride];
          tmp[idx] = v;
        }
    out.occupied.swap(tmp);
  }
  return out;
}

glm::dmat4 Normalisation::world_to_unit() const {
  glm::dmat4 m(scale);
  m[3] = glm::dvec4(-centre * scale, 1.0);
  return m;
}

glm::dmat4 Normalisation::unit_to_world() const {
  glm::dmat4 m(1.0 / scale);
  m[3] = glm::dvec4(centre, 1.0);
  return m;
}

Normalisation normalise_to_unit_sphere(const OccupancyGrid& hull, double margin) {
  if (!(margin >= 1.0) || !std::isfinite(margin))
    throw UsageError("normalise_to_unit_sphere: margin must be a finite number >= 1, got " + std::to_string(margin));
  if (hull.occupied_count() == 0) throw InputError("normalise_to_unit_sphere: the visual hull is empty");
  glm::dvec3 a, b;
  hull.occupied_bounds(a, b);
  Normalisation n;
  n.centre = 0.5 * (a + b);
  const double half_diagonal = 0.5 * glm::length(b - a);
  n.scale = 1.0 / (margin * half_diagonal);
  return n;
}

json to_json(const Normalisation& n) {
  return json{{"centre", {n.centre.x, n.centre.y, n.centre.z}}, {"scale", n.scale}};
}

Normalisation normalisation_from_json(const json& j, const std::string& source) {
  if (!j.is_object()) throw InputError(source + ": the normalisation must be a JSON object");
  Normalisation n;
  if (!j.contains("centre")) throw InputError(source + ": field 'centre' is missing");
  const json& c = j["centre"];
  if (!c.is_array() || c.size() != 3) throw InputError(source + ": field 'centre' must be an array of 3 numbers");
  for (int a = 0; a < 3; ++a) {
    if (!c[std::size_t(a)].is_number() || !std::isfinite(c[std::size_t(a)].get<double>()))
      throw InputError(source + ": field 'centre[" + std::to_string(a) + "]' must be a finite number");
    n.centre[a] = c[std::size_t(a)].get<double>();
  }
  if (!j.contains("scale")) throw InputError(source + ": field 'scale' is missing");
  const json& s = j["scale"];
  if (!s.is_number() || !std::isfinite(s.get<double>()) || !(s.get<double>() > 0))
    throw InputError(source + ": field 'scale' must be a positive finite number");
  n.scale = s.get<double>();
  return n;
}

}  // namespace nf::neus
