#include "engine/geometry/distance_transform.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"  // parallel_for

namespace nf::geometry {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// d[q] = min_p (step * (q - p))^2 + f[p] over the n samples of f (infinite entries are no
// candidates); d is +inf everywhere when all of f is. v, z: scratch of n and n + 1 entries.
void lower_envelope(const double* f, double* d, std::size_t n, double step, std::size_t* v, double* z) {
  const double s2 = step * step;
  std::ptrdiff_t k = -1;
  for (std::size_t q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    const double fq = f[q] + s2 * double(q) * double(q);
    double cut = -kInf;
    while (k >= 0) {
      const double p = double(v[k]);
      // Where the parabola of q starts to undercut that of v[k], in samples.
      cut = (fq - (f[v[k]] + s2 * p * p)) / (2 * s2 * (double(q) - p));
      if (cut > z[k]) break;
      --k;
    }
    if (k < 0) cut = -kInf;
    ++k;
    v[k] = q;
    z[k] = cut;
    z[k + 1] = kInf;
  }
  if (k < 0) {
    for (std::size_t q = 0; q < n; ++q) d[q] = kInf;
    return;
  }
  std::ptrdiff_t j = 0;
  for (std::size_t q = 0; q < n; ++q) {
    while (z[j + 1] < double(q)) ++j;
    const double dq = double(q) - double(v[j]);
    d[q] = s2 * dq * dq + f[v[j]];
  }
}

}  // namespace

std::vector<float> distance_transform(const std::vector<std::uint8_t>& mask, glm::ivec3 dims, glm::vec3 voxel_size) {
  if (dims.x < 0 || dims.y < 0 || dims.z < 0)
    throw InputError("distance_transform: negative grid size " + std::to_string(dims.x) + "x" + std::to_string(dims.y) +
                     "x" + std::to_string(dims.z));
  for (int a = 0; a < 3; ++a)
    if (!(voxel_size[a] > 0.f) || !std::isfinite(voxel_size[a]))
      throw InputError("distance_transform: voxel size on axis " + std::to_string(a) + " is " +
                       std::to_string(voxel_size[a]) + ", not a positive number");
  const std::size_t n[3] = {std::size_t(dims.x), std::size_t(dims.y), std::size_t(dims.z)};
  const std::size_t count = n[0] * n[1] * n[2];
  if (mask.size() != count)
    throw InputError("distance_transform: the mask has " + std::to_string(mask.size()) + " entries, the grid " +
                     std::to_string(count));
  std::vector<float> out(count);
  if (count == 0) return out;
  const std::size_t stride[3] = {1, n[0], n[0] * n[1]};

  // Squared distances in `out` between passes (float; each pass works in double along its line).
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;  // the other two axes
    const std::size_t len = n[axis], lines = n[a1] * n[a2];
    parallel_for(lines, [&](std::size_t begin, std::size_t end) {
      std::vector<double> f(len), d(len), z(len + 1);
      std::vector<std::size_t> v(len);
      for (std::size_t line = begin; line < end; ++line) {
        const std::size_t base = (line % n[a1]) * stride[a1] + (line / n[a1]) * stride[a2];
        for (std::size_t i = 0; i < len; ++i) {
          const std::size_t at = base + i * stride[axis];
          f[i] = axis == 0 ? (mask[at] ? 0.0 : kInf) : double(out[at]);
        }
        lower_envelope(f.data(), d.data(), len, double(voxel_size[axis]), v.data(), z.data());
        for (std::size_t i = 0; i < len; ++i) {
          const std::size_t at = base + i * stride[axis];
          out[at] = axis == 2 ? float(std::sqrt(d[i])) : float(d[i]);
        }
      }
    });
  }
  return out;
}

}  // namespace nf::geometry
