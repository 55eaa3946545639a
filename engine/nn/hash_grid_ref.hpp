#pragma once
// CPU reference of the multiresolution hash-grid encoding (instant-ngp), one template for float
// and double; the GPU kernels follow it exactly (shaders/nn/hash_grid_{fwd,bwd}.comp).
//
// Level l has resolution N_l = floor(N_min * b^l), b = (N_max / N_min)^(1 / (L - 1)). A point
// x in [0, 1]^3 lies at p = x N_l; its cell's 8 vertices (integer, 0..N_l) are looked up in the
// level's table of T entries of F features: directly when (N_l + 1)^3 <= T, else by the spatial
// hash (i * 1 ^ j * 2654435761 ^ k * 805459861) mod T. Features are trilinear blends of the 8.
// Output row: [l * F + f], padded to a multiple of 4. Points outside [0, 1] are clamped.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::nn {

struct HashGridConfig {
  std::uint32_t levels = 16;
  std::uint32_t features = 2;       // per level: 1, 2 or 4
  std::uint32_t log2_table = 19;
  std::uint32_t base_resolution = 16;
  std::uint32_t max_resolution = 2048;

  std::uint32_t table_size() const { return 1u << log2_table; }
  std::uint32_t output_dim() const { return levels * features; }
  std::uint32_t output_stride() const { return (output_dim() + 3u) & ~3u; }
  std::uint64_t parameter_count() const { return std::uint64_t(levels) * table_size() * features; }
  std::uint32_t resolution(std::uint32_t level) const {
    if (levels <= 1) return base_resolution;
    const double b = std::exp((std::log(double(max_resolution)) - std::log(double(base_resolution))) / (levels - 1));
    return std::uint32_t(std::floor(base_resolution * std::pow(b, double(level)) + 1e-6));
  }
  bool dense(std::uint32_t level) const {
    const std::uint64_t n = std::uint64_t(resolution(level)) + 1;
    return n * n * n <= table_size();
  }
};

inline std::uint32_t hash_grid_index(const HashGridConfig& c, std::uint32_t level, std::uint32_t i, std::uint32_t j,
                                     std::uint32_t k) {
  const std::uint32_t n = c.resolution(level) + 1;
  if (c.dense(level)) return i + j * n + k * n * n;
  return (i * 1u ^ j * 2654435761u ^ k * 805459861u) & (c.table_size() - 1u);
}

// Cell and fraction of a coordinate at resolution n.
template <class T>
void hash_grid_cell(T x, std::uint32_t n, std::uint32_t& cell, T& frac) {
  const T p = std::clamp(x, T(0), T(1)) * T(n);
  const T f = std::floor(p);
  cell = std::min(std::uint32_t(f), n - 1);
  frac = p - T(cell);
}

// One of the 8 vertices of the cell holding point s at level l: its table entry (first feature),
// trilinear weight and the weight's derivative along each axis (per unit of x, before scaling by N).
template <class T>
struct HashGridCorner {
  std::uint64_t entry;
  T weight;
  T dweight[3];
};

template <class T>
HashGridCorner<T> hash_grid_corner(const HashGridConfig& c, std::uint32_t level, const std::uint32_t cell[3],
                                   const T frac[3], std::uint32_t corner) {
  HashGridCorner<T> k{0, T(1), {T(1), T(1), T(1)}};
  std::uint32_t v[3];
  for (int a = 0; a < 3; ++a) {
    const bool up = (corner >> a) & 1u;
    const T wa = up ? frac[a] : T(1) - frac[a];
    k.weight *= wa;
    for (int b = 0; b < 3; ++b) k.dweight[b] *= b == a ? (up ? T(1) : T(-1)) : wa;
    v[a] = cell[a] + (up ? 1u : 0u);
  }
  k.entry = (std::uint64_t(level) * c.table_size() + hash_grid_index(c, level, v[0], v[1], v[2])) * c.features;
  return k;
}

// points: [batch][3]; table: parameter_count(); returns [batch][output_stride].
template <class T>
std::vector<T> hash_grid_forward_ref(const HashGridConfig& c, const std::vector<T>& points, const std::vector<T>& table,
                                     std::uint32_t batch) {
  std::vector<T> out(std::size_t(c.output_stride()) * batch, T(0));
  for (std::uint32_t s = 0; s < batch; ++s)
    for (std::uint32_t l = 0; l < c.levels; ++l) {
      std::uint32_t cell[3];
      T frac[3];
      for (int a = 0; a < 3; ++a) hash_grid_cell(points[std::size_t(s) * 3 + a], c.resolution(l), cell[a], frac[a]);
      for (std::uint32_t corner = 0; corner < 8; ++corner) {
        const HashGridCorner<T> k = hash_grid_corner(c, l, cell, frac, corner);
        for (std::uint32_t f = 0; f < c.features; ++f)
          out[std::size_t(s) * c.output_stride() + l * c.features + f] += k.weight * table[k.entry + f];
      }
    }
  return out;
}

// Adjoint: grad_table (+)= dL/dtable; returns dL/dpoints ([batch][3]; zero where a point is clamped).
template <class T>
std::vector<T> hash_grid_backward_ref(const HashGridConfig& c, const std::vector<T>& points, const std::vector<T>& table,
                                      std::uint32_t batch, const std::vector<T>& grad_out, std::vector<T>& grad_table) {
  grad_table.resize(table.size(), T(0));
  std::vector<T> grad_points(points.size(), T(0));
  for (std::uint32_t s = 0; s < batch; ++s)
    for (std::uint32_t l = 0; l < c.levels; ++l) {
      const std::uint32_t n = c.resolution(l);
      std::uint32_t cell[3];
      T frac[3];
      for (int a = 0; a < 3; ++a) hash_grid_cell(points[std::size_t(s) * 3 + a], n, cell[a], frac[a]);
      for (std::uint32_t corner = 0; corner < 8; ++corner) {
        const HashGridCorner<T> k = hash_grid_corner(c, l, cell, frac, corner);
        for (std::uint32_t f = 0; f < c.features; ++f) {
          const T g = grad_out[std::size_t(s) * c.output_stride() + l * c.features + f];
          grad_table[k.entry + f] += k.weight * g;
          for (int a = 0; a < 3; ++a) {
            const T x = points[std::size_t(s) * 3 + a];
            if (x >= T(0) && x <= T(1)) grad_points[std::size_t(s) * 3 + a] += g * table[k.entry + f] * k.dweight[a] * T(n);
          }
        }
      }
    }
  return grad_points;
}

}  // namespace nf::nn
