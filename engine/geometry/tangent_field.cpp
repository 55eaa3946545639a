#include "engine/geometry/tangent_field.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <deque>
#include <unordered_map>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "engine/core/error.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::geometry {
namespace {


struct FaceEdge {
  std::uint32_t f, g;   // the two faces
  std::uint32_t a, b;   // the shared edge's vertices
};

// Interior edges shared by exactly two faces.
std::vector<FaceEdge> face_adjacency(const Mesh& mesh) {
  std::unordered_map<std::uint64_t, std::pair<std::uint32_t, int>> first;  // edge -> (face, uses)
  first.reserve(3 * mesh.triangle_count());
  std::vector<FaceEdge> edges;
  std::unordered_map<std::uint64_t, std::size_t> edge_index;
  for (std::uint32_t f = 0; f < mesh.triangle_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[3 * std::size_t(f) + std::size_t(k)],
                          b = mesh.triangles[3 * std::size_t(f) + std::size_t(k + 1) % 3];
      const std::uint64_t key = a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
      auto [it, fresh] = first.try_emplace(key, f, 1);
      if (fresh) continue;
      if (++it->second.second == 2) {
        edge_index[key] = edges.size();
        edges.push_back({it->second.first, f, a, b});
      } else if (it->second.second == 3) {
        edges[edge_index[key]].g = it->second.first;  // non-manifold: marked unused below
      }
    }
  edges.erase(std::remove_if(edges.begin(), edges.end(), [](const FaceEdge& e) { return e.f == e.g; }), edges.end());
  return edges;
}

struct FaceBasis {
  glm::dvec3 e1{0.0}, e2{0.0}, n{0.0};
  double area = 0;
};

std::vector<FaceBasis> face_bases(const Mesh& mesh) {
  std::vector<FaceBasis> out(mesh.triangle_count());
  for (std::size_t f = 0; f < out.size(); ++f) {
    const glm::dvec3 a = glm::dvec3(mesh.position(mesh.triangles[3 * f])), b = glm::dvec3(mesh.position(mesh.triangles[3 * f + 1])),
                     c = glm::dvec3(mesh.position(mesh.triangles[3 * f + 2]));
    const glm::dvec3 cr = glm::cross(b - a, c - a);
    const double len = glm::length(cr);
    if (!(len > 0) || !(glm::length(b - a) > 0)) continue;
    out[f].n = cr / len;
    out[f].e1 = glm::normalize(b - a);
    out[f].e2 = glm::cross(out[f].n, out[f].e1);
    out[f].area = 0.5 * len;
  }
  return out;
}

// A tangent of face f carried across the edge (a, b) into face g: its components along the edge
// and across it (in each face's plane) are kept.
glm::dvec3 carry(const glm::dvec3& t, const FaceBasis& f, const FaceBasis& g, const glm::dvec3& edge) {
  const glm::dvec3 e = glm::normalize(edge);
  return glm::dot(t, e) * e + glm::dot(t, glm::cross(f.n, e)) * glm::cross(g.n, e);
}

}  // namespace

TangentField smooth_tangent_field(const Mesh& mesh, std::span<const glm::vec3> guides, const TangentFieldOptions& options) {
  const std::size_t nf = mesh.triangle_count();
  if (guides.size() != nf)
    throw InputError("tangent field: " + std::to_string(guides.size()) + " guides for " + std::to_string(nf) + " faces");
  for (std::size_t f = 0; f < nf; ++f)
    if (!std::isfinite(guides[f].x) || !std::isfinite(guides[f].y) || !std::isfinite(guides[f].z))
      throw InputError("tangent field: the guide of face " + std::to_string(f) + " is not finite");
  const Stopwatch clock;
  TangentField out;
  out.tangent.assign(nf, glm::vec3(0.f));
  out.normal.assign(nf, glm::vec3(0.f));
  if (nf == 0) return out;
  const std::vector<FaceBasis> basis = face_bases(mesh);
  const std::vector<FaceEdge> edges = face_adjacency(mesh);
  const double length = options.smoothing_length > 0 ? options.smoothing_length : 0.02 * double(mesh_bounds(mesh).diagonal());
  if (!(length > 0) || !std::isfinite(length)) throw InputError("tangent field: the smoothing length must be positive");

  double mean_area = 0;
  for (const FaceBasis& b : basis) mean_area += b.area;
  mean_area /= double(nf);
  if (!(mean_area > 0)) return out;  // no face has area: no tangent plane anywhere
  const double min_area = 1e-9 * mean_area;

  // Unknowns: (Re, Im) of u_f, interleaved.
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> entries;
  entries.reserve(8 * edges.size() + 2 * nf);
  std::vector<double> diagonal(2 * nf, 0.0);
  for (const FaceEdge& e : edges) {
    const FaceBasis &f = basis[e.f], &g = basis[e.g];
    if (f.area <= 0 || g.area <= 0) continue;
    const glm::dvec3 d = glm::dvec3(mesh.position(e.b)) - glm::dvec3(mesh.position(e.a));
    const double theta_f = std::atan2(glm::dot(d, f.e2), glm::dot(d, f.e1));
    const double theta_g = std::atan2(glm::dot(d, g.e2), glm::dot(d, g.e1));
    const double c = std::cos(theta_g - theta_f), s = std::sin(theta_g - theta_f);
    const double w = 1.5 * glm::dot(d, d) / std::max(f.area + g.area, min_area);
    const int F = 2 * int(e.f), G = 2 * int(e.g);
    for (int k = 0; k < 2; ++k) diagonal[std::size_t(F + k)] += w, diagonal[std::size_t(G + k)] += w;
    // -w R at (g, f) and -w R^T at (f, g), R = [[c, -s], [s, c]].
    const double R[2][2]{{c, -s}, {s, c}};
    for (int r = 0; r < 2; ++r)
      for (int q = 0; q < 2; ++q) {
        entries.emplace_back(G + r, F + q, -w * R[r][q]);
        entries.emplace_back(F + q, G + r, -w * R[r][q]);
      }
  }
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(Eigen::Index(2 * nf));
  for (std::size_t f = 0; f < nf; ++f) {
    const FaceBasis& b = basis[f];
    const glm::dvec3 q = glm::dvec3(guides[f]) - glm::dot(glm::dvec3(guides[f]), b.n) * b.n;
    const double norm = glm::length(glm::dvec3(guides[f]));
    // A guide along the normal says nothing about the tangent: not a guide.
    if (b.area <= 0 || !(norm > 0) || !(glm::length(q) > 1e-6 * norm)) continue;
    ++out.guided_faces;
    const double lambda = b.area / (length * length);
    const glm::dvec3 unit = q / norm;  // the guide's tangent part, shorter where it leans out
    diagonal[2 * f] += lambda, diagonal[2 * f + 1] += lambda;
    rhs[Eigen::Index(2 * f)] = lambda * glm::dot(unit, b.e1);
    rhs[Eigen::Index(2 * f + 1)] = lambda * glm::dot(unit, b.e2);
  }
  // A small shift keeps every component (and faces without area) definite; it is far below the
  // guides' weight, so it does not pull the field.
  const double shift = 1e-8 * mean_area / (length * length);
  for (std::size_t i = 0; i < 2 * nf; ++i) entries.emplace_back(int(i), int(i), diagonal[i] + shift);
  Eigen::SparseMatrix<double> A(Eigen::Index(2 * nf), Eigen::Index(2 * nf));
  A.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success) throw InternalError("tangent field: the sparse factorisation failed");
  Eigen::VectorXd u;
  if (out.guided_faces > 0) {
    u = solver.solve(rhs);
  } else {
    // Smoothest field: inverse iteration on L u = lambda M u from a fixed start.
    u = Eigen::VectorXd::Zero(Eigen::Index(2 * nf));
    for (std::size_t f = 0; f < nf; ++f) u[Eigen::Index(2 * f)] = 1.0 + 0.01 * double(f % 7), u[Eigen::Index(2 * f + 1)] = 0.3;
    for (int it = 0; it < options.eigen_iterations; ++it) {
      Eigen::VectorXd mu(u.size());
      for (std::size_t f = 0; f < nf; ++f)
        for (int k = 0; k < 2; ++k) mu[Eigen::Index(2 * f + std::size_t(k))] = std::max(basis[f].area, min_area) * u[Eigen::Index(2 * f + std::size_t(k))];
      u = solver.solve(mu);
      const double n = u.norm();
      if (!(n > 0) || !std::isfinite(n)) break;
      u /= n;
    }
  }
  if (solver.info() != Eigen::Success) throw InternalError("tangent field: the sparse solve failed");

  // Magnitudes: faces far below the typical one (components without guides, exact singularities)
  // get their direction from their neighbours instead.
  std::vector<double> magnitude(nf, 0.0);
  for (std::size_t f = 0; f < nf; ++f) magnitude[f] = std::hypot(u[Eigen::Index(2 * f)], u[Eigen::Index(2 * f + 1)]);
  std::vector<double> sorted_mag = magnitude;
  std::nth_element(sorted_mag.begin(), sorted_mag.begin() + std::ptrdiff_t(nf / 2), sorted_mag.end());
  const double floor = 1e-9 * sorted_mag[nf / 2];
  std::vector<std::uint8_t> known(nf, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    const FaceBasis& b = basis[f];
    out.normal[f] = glm::vec3(b.n);
    if (b.area <= 0 || !(magnitude[f] > floor) || !std::isfinite(magnitude[f])) continue;
    const glm::dvec3 t = (u[Eigen::Index(2 * f)] * b.e1 + u[Eigen::Index(2 * f + 1)] * b.e2) / magnitude[f];
    out.tangent[f] = glm::vec3(t);
    known[f] = 1;
  }
  // Breadth-first fill across shared edges, first from every face the solve gave a direction.
  std::vector<std::vector<std::uint32_t>> around(nf);
  for (std::size_t k = 0; k < edges.size(); ++k) around[edges[k].f].push_back(std::uint32_t(k)), around[edges[k].g].push_back(std::uint32_t(k));
  std::deque<std::uint32_t> queue;
  const auto spread = [&] {
    while (!queue.empty()) {
      const std::uint32_t f = queue.front();
      queue.pop_front();
      for (std::uint32_t k : around[f]) {
        const FaceEdge& e = edges[k];
        const std::uint32_t g = e.f == f ? e.g : e.f;
        if (known[g] || basis[g].area <= 0) continue;
        const glm::dvec3 t = carry(glm::dvec3(out.tangent[f]), basis[f], basis[g], glm::dvec3(mesh.position(e.b)) - glm::dvec3(mesh.position(e.a)));
        if (!(glm::length(t) > 0)) continue;
        out.tangent[g] = glm::vec3(glm::normalize(t));
        known[g] = 1, ++out.filled_faces;
        queue.push_back(g);
      }
    }
  };
  for (std::uint32_t f = 0; f < nf; ++f)
    if (known[f]) queue.push_back(f);
  spread();
  // Components the solve left without any direction (no guide reached them): seed one face with
  // its first edge and carry it on, so the component is still consistent.
  for (std::uint32_t seed = 0; seed < nf; ++seed) {
    if (known[seed] || basis[seed].area <= 0) continue;
    out.tangent[seed] = glm::vec3(basis[seed].e1);
    known[seed] = 1, ++out.filled_faces;
    queue.push_back(seed);
    spread();
  }
  out.solve_seconds = clock.seconds();
  return out;
}

FieldSmoothness field_smoothness(const Mesh& mesh, const std::vector<glm::vec3>& tangent) {
  if (tangent.size() != mesh.triangle_count())
    throw InputError("field smoothness: " + std::to_string(tangent.size()) + " tangents for " + std::to_string(mesh.triangle_count()) + " faces");
  FieldSmoothness s;
  const std::vector<FaceBasis> basis = face_bases(mesh);
  std::vector<double> angles;
  for (const FaceEdge& e : face_adjacency(mesh)) {
    if (basis[e.f].area <= 0 || basis[e.g].area <= 0) continue;
    if (!(glm::length(tangent[e.f]) > 0) || !(glm::length(tangent[e.g]) > 0)) continue;
    const glm::dvec3 t = carry(glm::dvec3(tangent[e.f]), basis[e.f], basis[e.g], glm::dvec3(mesh.position(e.b)) - glm::dvec3(mesh.position(e.a)));
    const double c = glm::dot(glm::normalize(t), glm::normalize(glm::dvec3(tangent[e.g])));
    angles.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
  }
  s.edges = angles.size();
  if (angles.empty()) return s;
  for (double a : angles) s.mean_angle_deg += a, s.flipped_edges += a > 90.0;
  s.mean_angle_deg /= double(angles.size());
  const std::size_t k = std::min(angles.size() - 1, std::size_t(0.95 * double(angles.size())));
  std::nth_element(angles.begin(), angles.begin() + std::ptrdiff_t(k), angles.end());
  s.p95_angle_deg = angles[k];
  return s;
}

json to_json(const FieldSmoothness& s) {
  return {{"edges", s.edges}, {"mean_angle_deg", s.mean_angle_deg}, {"p95_angle_deg", s.p95_angle_deg},
          {"flipped_edges", s.flipped_edges}};
}

}  // namespace nf::geometry
