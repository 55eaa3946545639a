#pragma once
// Fur roots: points spread uniformly over the area of M_bald's faces that grow fur, each with its
// face, barycentric coordinates, the face's frame (tangent, bitangent = normal x tangent, normal),
// region, fur length and growth direction interpolated from the vertices. Stratified: the samples
// split the fur's cumulative area into equal strata with one jittered sample each, and place it in
// its face by a jittered R2 low-discrepancy sequence, so roots neither clump nor leave gaps. A face
// grows fur when at least two of its vertices do; its length and direction interpolate the growing
// vertices only.
#include <cstdint>
#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "engine/defur/vertex_fur.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::fur {

struct Roots {
  std::vector<std::uint32_t> face;
  std::vector<glm::vec3> barycentric, position, tangent, bitangent, normal, direction;
  std::vector<std::int32_t> region;
  std::vector<float> length;  // scene units
  std::size_t size() const { return face.size(); }
};

// The faces' frames: per-face unit tangent and normal (geometry/tangent_field.hpp).
struct FaceFrames {
  std::vector<glm::vec3> tangent, normal;
};

// `count` roots (none when no face grows fur). Same inputs and seed: same roots.
Roots sample_roots(const geometry::Mesh& mesh, const FaceFrames& frames, const defur::VertexFur& fur, std::uint64_t count,
                   unsigned seed);
// The faces that grow fur.
std::vector<std::uint8_t> fur_faces(const geometry::Mesh& mesh, const defur::VertexFur& fur);
// Their total area (scene units squared).
double fur_area(const geometry::Mesh& mesh, const defur::VertexFur& fur);
// Per face, the unit mean growth direction of its vertices where the face grows fur, else 0: the
// tangent field's guides.
std::vector<glm::vec3> face_growth_guides(const geometry::Mesh& mesh, const defur::VertexFur& fur);

// roots.npz: face (u4), barycentric, position, tangent, bitangent, normal, direction (f4, n x 3),
// region (i4), length (f4). The reader checks every array's shape and values, naming the file.
void write_roots(const std::filesystem::path& file, const Roots& roots);
Roots read_roots(const std::filesystem::path& file);

}  // namespace nf::fur
