#include "engine/defur/sdf_file.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/npz.hpp"

namespace nf::defur {

SdfFile bald_body_sdf(const geometry::Mesh& bald, int resolution, const std::string& name) {
  geometry::SdfOptions options;
  options.resolution = resolution;
  options.band = 8.f * geometry::mesh_bounds(bald).longest() / float(resolution - 1);
  geometry::SignedDistanceGrid sdf = geometry::signed_distance_grid(bald, options, name);
  return {sdf.grid, sdf.band, std::move(sdf.distance)};
}

void write_sdf_file(const std::filesystem::path& file, const SdfFile& sdf) {
  const glm::ivec3 d = sdf.grid.dims;
  io::NpyWrite values{"sdf", {std::uint64_t(d.z), std::uint64_t(d.y), std::uint64_t(d.x)}, "<f4",
                      std::vector<double>(sdf.values.begin(), sdf.values.end())};
  io::NpyWrite origin{"origin", {3}, "<f8", {sdf.grid.origin.x, sdf.grid.origin.y, sdf.grid.origin.z}};
  io::NpyWrite spacing{"spacing", {1}, "<f8", {sdf.grid.voxel}};
  io::NpyWrite band{"band", {1}, "<f8", {sdf.band}};
  io::write_npz(file, {values, origin, spacing, band});
}

SdfFile read_sdf_file(const std::filesystem::path& file) {
  const io::NpyArray values = io::read_npz_array(file, "sdf"), origin = io::read_npz_array(file, "origin"),
                     spacing = io::read_npz_array(file, "spacing"), band = io::read_npz_array(file, "band");
  const auto fail = [&](const std::string& what) { throw InputError(file.string() + ": " + what); };
  if (values.shape.size() != 3) fail("array 'sdf' must have 3 dimensions (nz, ny, nx)");
  if (origin.values.size() != 3) fail("array 'origin' must hold 3 values");
  if (spacing.values.size() != 1 || !(spacing.values[0] > 0) || !std::isfinite(spacing.values[0])) fail("array 'spacing' must hold one positive value");
  if (band.values.size() != 1 || !(band.values[0] > 0) || !std::isfinite(band.values[0])) fail("array 'band' must hold one positive value");
  SdfFile out;
  for (int a = 0; a < 3; ++a) {
    if (values.shape[std::size_t(2 - a)] < 2 || values.shape[std::size_t(2 - a)] > 100000) fail("array 'sdf' has a dimension outside 2..100000");
    out.grid.dims[a] = int(values.shape[std::size_t(2 - a)]);
    if (!std::isfinite(origin.values[std::size_t(a)])) fail("array 'origin' is not finite");
    out.grid.origin[a] = float(origin.values[std::size_t(a)]);
  }
  out.grid.voxel = float(spacing.values[0]);
  out.band = float(band.values[0]);
  out.values.resize(values.values.size());
  for (std::size_t i = 0; i < values.values.size(); ++i) {
    if (!std::isfinite(values.values[i])) fail("array 'sdf' value " + std::to_string(i) + " is not finite");
    out.values[i] = float(values.values[i]);
  }
  return out;
}

}  // namespace nf::defur
