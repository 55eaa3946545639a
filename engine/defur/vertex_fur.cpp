#include "engine/defur/vertex_fur.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/geometry/vertex_smoothing.hpp"
#include "engine/io/npz.hpp"

namespace nf::defur {

VertexFur vertex_fur(const geometry::Mesh& mesh, const knowledge::Knowledge& knowledge,
                     const std::array<glm::vec3, body::kRegionCount>& directions_world, double cm_per_unit,
                     int smoothing_iterations) {
  NF_CHECK(mesh.regions.size() == mesh.vertex_count(), "vertex_fur: regions per vertex");
  NF_CHECK(cm_per_unit > 0, "vertex_fur: positive scale");
  const std::size_t n = mesh.vertex_count();
  VertexFur fur;
  fur.region = mesh.regions;
  std::vector<float> length(n, 0.f), direction(3 * n, 0.f);
  std::vector<std::uint8_t> active(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    const auto r = body::Region(mesh.regions[v]);
    if (!knowledge.grows_fur(r)) continue;
    active[v] = 1;
    length[v] = float(knowledge.at(r).length_cm / cm_per_unit);
    const glm::vec3 d = directions_world[std::size_t(r)];
    for (int c = 0; c < 3; ++c) direction[3 * v + std::size_t(c)] = d[c];
  }
  geometry::smooth_vertex_values(mesh, length, 1, smoothing_iterations, active);
  geometry::smooth_vertex_values(mesh, direction, 3, smoothing_iterations, active);
  fur.length = std::move(length);
  fur.direction.assign(n, glm::vec3(0.f));
  for (std::size_t v = 0; v < n; ++v) {
    const glm::vec3 d(direction[3 * v], direction[3 * v + 1], direction[3 * v + 2]);
    const float l = glm::length(d);
    if (active[v] && l > 1e-6f) fur.direction[v] = d / l;
  }
  return fur;
}

void write_vertex_fur(const std::filesystem::path& file, const VertexFur& fur) {
  const std::uint64_t n = fur.size();
  io::NpyWrite region{"region", {n}, "<i4", {}}, length{"length", {n}, "<f4", {}}, direction{"direction", {n, 3}, "<f4", {}};
  for (std::size_t v = 0; v < n; ++v) {
    region.values.push_back(fur.region[v]);
    length.values.push_back(fur.length[v]);
    for (int c = 0; c < 3; ++c) direction.values.push_back(fur.direction[v][c]);
  }
  io::write_npz(file, {region, length, direction});
}

VertexFur read_vertex_fur(const std::filesystem::path& file, std::size_t vertex_count) {
  const auto array = [&](const char* name, std::uint64_t columns) {
    io::NpyArray a = io::read_npz_array(file, name);
    const std::uint64_t expected = columns * vertex_count;
    if (a.values.size() != expected)
      throw InputError(file.string() + ": array '" + name + "' has " + std::to_string(a.values.size()) + " values; the mesh needs " +
                       std::to_string(expected) + " (" + std::to_string(vertex_count) + " vertices)");
    for (std::size_t i = 0; i < a.values.size(); ++i)
      if (!std::isfinite(a.values[i])) throw InputError(file.string() + ": array '" + name + "' value " + std::to_string(i) + " is not finite");
    return a;
  };
  const io::NpyArray region = array("region", 1), length = array("length", 1), direction = array("direction", 3);
  VertexFur fur;
  fur.region.resize(vertex_count), fur.length.resize(vertex_count), fur.direction.resize(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const double r = region.values[v];
    if (r < 0 || r >= body::kRegionCount || r != std::floor(r))
      throw InputError(file.string() + ": array 'region' value " + std::to_string(v) + " is not a region id");
    if (length.values[v] < 0) throw InputError(file.string() + ": array 'length' value " + std::to_string(v) + " is negative");
    fur.region[v] = std::int32_t(r), fur.length[v] = float(length.values[v]);
    fur.direction[v] = glm::vec3(direction.values[3 * v], direction.values[3 * v + 1], direction.values[3 * v + 2]);
  }
  return fur;
}

}  // namespace nf::defur
