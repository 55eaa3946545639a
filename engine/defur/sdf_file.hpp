#pragma once
// The bald body's signed distance grid as a file (bald_sdf.npz) for the fur stage's penetration
// loss: `sdf` (f4, shape nz x ny x nx: x fastest), `origin` (3), `spacing` (1), `band` (1). Sample
// (i, j, k) lies at origin + spacing * (i, j, k); negative inside; |sdf| exact within `band`.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/geometry/mesh_sdf.hpp"

namespace nf::defur {

struct SdfFile {
  geometry::GridSpec grid;
  float band = 0;
  std::vector<float> values;
};

// M_bald's grid as the fur stage reads it: `resolution` samples along the box's longest side and
// exact distances within 8 voxels of the surface (what the penetration loss needs; beyond the band
// a sunk point is pulled at the band's depth). `name` names the mesh in errors.
SdfFile bald_body_sdf(const geometry::Mesh& bald, int resolution, const std::string& name);
void write_sdf_file(const std::filesystem::path& file, const SdfFile& sdf);
// InputError naming the file and array when shapes disagree or values are not finite.
SdfFile read_sdf_file(const std::filesystem::path& file);

}  // namespace nf::defur
