#include "engine/fur/roots.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/io/npz.hpp"

namespace nf::fur {
std::vector<std::uint8_t> fur_faces(const geometry::Mesh& mesh, const defur::VertexFur& fur) {
  NF_CHECK(fur.size() == mesh.vertex_count(), "fur_faces: knowledge per vertex");
  std::vector<std::uint8_t> out(mesh.triangle_count(), 0);
  for (std::size_t f = 0; f < out.size(); ++f) {
    int growing = 0;
    for (int k = 0; k < 3; ++k) growing += fur.grows(mesh.triangles[3 * f + std::size_t(k)]);
    out[f] = growing >= 2;
  }
  return out;
}

double fur_area(const geometry::Mesh& mesh, const defur::VertexFur& fur) {
  const std::vector<std::uint8_t> growing = fur_faces(mesh, fur);
  double area = 0;
  for (std::size_t f = 0; f < growing.size(); ++f)
    if (growing[f]) {
      const std::uint32_t* v = &mesh.triangles[3 * f];
      area += 0.5 * double(glm::length(glm::cross(mesh.position(v[1]) - mesh.position(v[0]), mesh.position(v[2]) - mesh.position(v[0]))));
    }
  return area;
}

std::vector<glm::vec3> face_growth_guides(const geometry::Mesh& mesh, const defur::VertexFur& fur) {
  const std::vector<std::uint8_t> growing = fur_faces(mesh, fur);
  std::vector<glm::vec3> guides(mesh.triangle_count(), glm::vec3(0.f));
  for (std::size_t f = 0; f < guides.size(); ++f) {
    if (!growing[f]) continue;
    glm::vec3 sum(0.f);
    for (int k = 0; k < 3; ++k) sum += fur.direction[mesh.triangles[3 * f + std::size_t(k)]];
    if (glm::length(sum) > 0) guides[f] = glm::normalize(sum);
  }
  return guides;
}

Roots sample_roots(const geometry::Mesh& mesh, const FaceFrames& frames, const defur::VertexFur& fur, std::uint64_t count,
                   unsigned seed) {
  const std::size_t nf = mesh.triangle_count();
  NF_CHECK(frames.tangent.size() == nf && frames.normal.size() == nf, "sample_roots: a frame per face");
  const std::vector<std::uint8_t> growing = fur_faces(mesh, fur);
  std::vector<double> cumulative(nf + 1, 0.0);
  for (std::size_t f = 0; f < nf; ++f) {
    double area = 0;
    if (growing[f]) {
      const std::uint32_t* v = &mesh.triangles[3 * f];
      area = 0.5 * double(glm::length(glm::cross(mesh.position(v[1]) - mesh.position(v[0]), mesh.position(v[2]) - mesh.position(v[0]))));
      if (!std::isfinite(area) || glm::length(frames.tangent[f]) == 0.f) area = 0;
    }
    cumulative[f + 1] = cumulative[f] + area;
  }
  Roots roots;
  const double total = cumulative[nf];
  if (!(total > 0) || count == 0) return roots;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // R2 sequence (Roberts 2018): the plastic number's powers give a 2D sequence with low discrepancy.
  const double g = 1.32471795724474602596, a1 = 1.0 / g, a2 = 1.0 / (g * g);
  const double o1 = unit(rng), o2 = unit(rng);
  const auto reserve = [&](auto& v) { v.reserve(count); };
  reserve(roots.face), reserve(roots.barycentric), reserve(roots.position), reserve(roots.tangent), reserve(roots.bitangent);
  reserve(roots.normal), reserve(roots.direction), reserve(roots.region), reserve(roots.length);
  for (std::uint64_t k = 0; k < count; ++k) {
    const double target = (double(k) + unit(rng)) / double(count) * total;
    std::size_t f = std::size_t(std::upper_bound(cumulative.begin() + 1, cumulative.end(), target) - cumulative.begin()) - 1;
    f = std::min(f, nf - 1);
    while (f > 0 && !(cumulative[f + 1] > cumulative[f])) --f;  // never land on a face without area
    const double u = std::fmod(o1 + a1 * double(k), 1.0), w = std::fmod(o2 + a2 * double(k), 1.0);
    const double su = std::sqrt(u);
    glm::vec3 b(float(1 - su), float(su * (1 - w)), float(su * w));
    const std::uint32_t* v = &mesh.triangles[3 * f];
    // Length and direction from the growing vertices only.
    float weight = 0, length = 0;
    glm::vec3 direction(0.f);
    int best = 0;
    for (int c = 0; c < 3; ++c) {
      if (!fur.grows(v[c])) continue;
      weight += b[c], length += b[c] * fur.length[v[c]], direction += b[c] * fur.direction[v[c]];
      if (!fur.grows(v[best]) || b[c] > b[best]) best = c;
    }
    if (weight <= 0) {  // the sample sits on the bald corner: take the growing vertices' mean
      weight = 0, length = 0, direction = glm::vec3(0.f);
      for (int c = 0; c < 3; ++c)
        if (fur.grows(v[c])) weight += 1, length += fur.length[v[c]], direction += fur.direction[v[c]];
    }
    length /= weight;
    const float dl = glm::length(direction);
    roots.face.push_back(std::uint32_t(f));
    roots.barycentric.push_back(b);
    roots.position.push_back(b.x * mesh.position(v[0]) + b.y * mesh.position(v[1]) + b.z * mesh.position(v[2]));
    roots.tangent.push_back(frames.tangent[f]);
    roots.normal.push_back(frames.normal[f]);
    roots.bitangent.push_back(glm::cross(frames.normal[f], frames.tangent[f]));
    roots.direction.push_back(dl > 0 ? direction / dl : frames.tangent[f]);
    roots.region.push_back(fur.region[v[best]]);
    roots.length.push_back(length);
  }
  return roots;
}

void write_roots(const std::filesystem::path& file, const Roots& r) {
  const std::uint64_t n = r.size();
  io::NpyWrite face{"face", {n}, "<u4", {}}, region{"region", {n}, "<i4", {}}, length{"length", {n}, "<f4", {}};
  for (std::size_t i = 0; i < n; ++i) face.values.push_back(r.face[i]), region.values.push_back(r.region[i]), length.values.push_back(r.length[i]);
  std::vector<io::NpyWrite> arrays{face};
  const auto vec3s = [&](const char* name, const std::vector<glm::vec3>& v) {
    io::NpyWrite a{name, {n, 3}, "<f4", {}};
    a.values.reserve(3 * n);
    for (const glm::vec3& x : v) a.values.insert(a.values.end(), {x.x, x.y, x.z});
    arrays.push_back(std::move(a));
  };
  vec3s("barycentric", r.barycentric), vec3s("position", r.position), vec3s("tangent", r.tangent);
  vec3s("bitangent", r.bitangent), vec3s("normal", r.normal), vec3s("direction", r.direction);
  arrays.push_back(region), arrays.push_back(length);
  io::write_npz(file, arrays);
}

Roots read_roots(const std::filesystem::path& file) {
  const std::size_t n = io::read_npz_array(file, "face").values.size();
  const auto array = [&](const char* name, std::size_t columns) {
    io::NpyArray a = io::read_npz_array(file, name);
    if (a.values.size() != n * columns)
      throw InputError(file.string() + ": array '" + name + "' has " + std::to_string(a.values.size()) + " values for " +
                       std::to_string(n) + " roots (expected " + std::to_string(n * columns) + ")");
    for (std::size_t i = 0; i < a.values.size(); ++i)
      if (!std::isfinite(a.values[i])) throw InputError(file.string() + ": array '" + name + "' value " + std::to_string(i) + " is not finite");
    return a;
  };
  Roots r;
  const auto vec3s = [&](const char* name, std::vector<glm::vec3>& out) {
    const io::NpyArray a = array(name, 3);
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = glm::vec3(a.values[3 * i], a.values[3 * i + 1], a.values[3 * i + 2]);
  };
  vec3s("barycentric", r.barycentric), vec3s("position", r.position), vec3s("tangent", r.tangent);
  vec3s("bitangent", r.bitangent), vec3s("normal", r.normal), vec3s("direction", r.direction);
  const io::NpyArray face = array("face", 1), region = array("region", 1), length = array("length", 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (face.values[i] < 0 || face.values[i] > 4294967295.0 || face.values[i] != std::floor(face.values[i]))
      throw InputError(file.string() + ": array 'face' value " + std::to_string(i) + " is not a face index");
    if (region.values[i] < 0 || region.values[i] >= body::kRegionCount || region.values[i] != std::floor(region.values[i]))
      throw InputError(file.string() + ": array 'region' value " + std::to_string(i) + " is not a region id");
    if (!(length.values[i] >= 0)) throw InputError(file.string() + ": array 'length' value " + std::to_string(i) + " is negative");
    r.face.push_back(std::uint32_t(face.values[i]));
    r.region.push_back(std::int32_t(region.values[i]));
    r.length.push_back(float(length.values[i]));
  }
  return r;
}

}  // namespace nf::fur
