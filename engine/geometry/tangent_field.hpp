#pragma once
// A smooth unit tangent direction per face of a triangle mesh, globally optimal in the sense of
// Knöppel, Crane, Pinkall and Schröder, "Globally Optimal Direction Fields" (SIGGRAPH 2013), for
// direction fields (n = 1), with soft alignment to per-face guide directions.
//
// Each face has a basis (e1 along its first edge, e2 = n x e1) in which a tangent vector is a
// complex number u_f. Crossing a shared edge, the Levi-Civita connection of the flattened pair of
// faces maps u_f to r_fg u_f, r_fg = exp(i (theta_g - theta_f)) with theta the shared edge's angle
// in each basis. The field minimises
//     sum over interior edges  w_e |u_g - r_fg u_f|^2  +  sum over guided faces  (A_f / l^2) |u_f - q_f|^2
// with w_e = 1.5 |e|^2 / (A_f + A_g) (the dual-edge weight of an equilateral mesh: the sum tends to
// the Dirichlet energy of the field) and q_f the guide projected onto the face's plane (its length,
// below 1 where the guide leans out of the surface, weighs it). Guides thus spread over about
// `smoothing_length` before their neighbours' pull wins. The system (L + Lambda) u = Lambda q is
// sparse, symmetric and positive definite (one Cholesky factorisation, Eigen). Without any guide the
// smoothest field is the eigenvector of L's smallest eigenvalue (inverse iteration, shifted). Faces
// the solve leaves without a direction (components with no guide) take their neighbours' directions
// carried across shared edges by the same connection, so neighbouring faces never disagree in sign.
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

struct TangentFieldOptions {
  double smoothing_length = 0;  // scene units; 0: 2 % of the mesh's bounding-box diagonal
  int eigen_iterations = 40;    // inverse iterations for an unguided field
};

struct TangentField {
  std::vector<glm::vec3> tangent;  // unit, in the face's plane (zero for a face without area)
  std::vector<glm::vec3> normal;   // unit face normals (zero for a face without area)
  std::uint64_t guided_faces = 0, filled_faces = 0;  // faces with a guide; faces given a neighbour's direction
  double solve_seconds = 0;
};

// guides: one world vector per face (zero: no guide). Throws InputError for a size mismatch,
// a non-finite guide or a non-positive smoothing length.
TangentField smooth_tangent_field(const Mesh& mesh, std::span<const glm::vec3> guides, const TangentFieldOptions& options = {});

struct FieldSmoothness {
  std::uint64_t edges = 0;        // interior edges between two faces with area
  double mean_angle_deg = 0;      // angle between a face's tangent carried across the edge and its neighbour's
  double p95_angle_deg = 0;
  std::uint64_t flipped_edges = 0;  // edges where that angle exceeds 90 degrees
};
FieldSmoothness field_smoothness(const Mesh& mesh, const std::vector<glm::vec3>& tangent);
json to_json(const FieldSmoothness& s);

}  // namespace nf::geometry
