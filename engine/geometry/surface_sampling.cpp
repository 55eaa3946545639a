#include "engine/geometry/surface_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace nf::geometry {

SurfaceSamples sample_surface(const geometry::Mesh& m, std::uint64_t count, unsigned seed) {
  const std::uint64_t faces = m.triangle_count();
  std::vector<double> cumulative(faces);
  std::vector<float> face_normals(faces * 3);
  double total = 0;
  for (std::uint64_t f = 0; f < faces; ++f) {
    const float* a = &m.positions[3 * std::size_t(m.triangles[3 * f])];
    const float* b = &m.positions[3 * std::size_t(m.triangles[3 * f + 1])];
    const float* c = &m.positions[3 * std::size_t(m.triangles[3 * f + 2])];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    total += 0.5 * len;
    cumulative[f] = total;
    for (int k = 0; k < 3; ++k) face_normals[3 * f + k] = len > 0 ? float(n[k] / len) : 0.f;
  }
  SurfaceSamples s;
  if (faces == 0 || !(total > 0)) return s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  s.points.reserve(count * 3);
  s.normals.reserve(count * 3);
  for (std::uint64_t i = 0; i < count; ++i) {
    const std::uint64_t f = std::min<std::uint64_t>(
        faces - 1, std::uint64_t(std::upper_bound(cumulative.begin(), cumulative.end(), uni(rng) * total) - cumulative.begin()));
    double r1 = uni(rng), r2 = uni(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;  // fold the square onto the triangle
    for (int k = 0; k < 3; ++k) {
      const float a = m.positions[3 * std::size_t(m.triangles[3 * f]) + k];
      const float b = m.positions[3 * std::size_t(m.triangles[3 * f + 1]) + k];
      const float c = m.positions[3 * std::size_t(m.triangles[3 * f + 2]) + k];
      s.points.push_back(float(a + r1 * (b - a) + r2 * (c - a)));
      s.normals.push_back(face_normals[3 * f + k]);
    }
  }
  return s;
}

}  // namespace nf::geometry
