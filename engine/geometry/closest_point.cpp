#include "engine/geometry/closest_point.hpp"

namespace nf::geometry {

namespace {

// The closest point of the triangle's three edges (for triangles without area).
TrianglePoint closest_on_edges(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  TrianglePoint best{a, {1, 0, 0}};
  float best_d = glm::dot(p - a, p - a);
  const glm::vec3 corners[3]{a, b, c};
  for (int e = 0; e < 3; ++e) {
    const glm::vec3 u = corners[e], w = corners[(e + 1) % 3], uw = w - u;
    const float len2 = glm::dot(uw, uw);
    const float t = len2 > 0 ? glm::clamp(glm::dot(p - u, uw) / len2, 0.f, 1.f) : 0.f;
    const glm::vec3 q = u + t * uw;
    const float d = glm::dot(p - q, p - q);
    if (d < best_d) {
      best_d = d, best.point = q, best.barycentric = glm::vec3(0);
      best.barycentric[e] = 1 - t, best.barycentric[(e + 1) % 3] = t;
    }
  }
  return best;
}

}  // namespace

TrianglePoint closest_point_on_triangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  // Coincident or collinear corners make the region tests divide by zero.
  const glm::vec3 n = glm::cross(ab, ac);
  if (!(glm::dot(n, n) > 1e-12f * glm::dot(ab, ab) * glm::dot(ac, ac))) return closest_on_edges(p, a, b, c);
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {a, {1, 0, 0}};
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {b, {0, 1, 0}};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
    const float v = d1 / (d1 - d3);
    return {a + v * ab, {1 - v, v, 0}};
  }
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {c, {0, 0, 1}};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {
    const float w = d2 / (d2 - d6);
    return {a + w * ac, {1 - w, 0, w}};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0 && (d4 - d3) + (d5 - d6) > 0) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), {0, 1 - w, w}};
  }
  const float sum = va + vb + vc;
  if (!(sum > 0)) return closest_on_edges(p, a, b, c);
  const float v = vb / sum, w = vc / sum;
  return {a + ab * v + ac * w, {1 - v - w, v, w}};
}

}  // namespace nf::geometry
