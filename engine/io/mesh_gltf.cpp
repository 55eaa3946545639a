// Meshes as glTF 2.0 (.glb, .gltf) through tinygltf; mesh.hpp lists what is read and what is
// refused. gltf_model.cpp parses the file and guarantees the types and indices used here; this file
// checks every byte range an accessor reads (counts, offsets, strides, with overflow-safe arithmetic)
// and every value (NaN, indices), flattens the scene and writes GLB.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <optional>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/gltf_model.hpp"
#include "engine/io/mesh.hpp"

namespace nf::io {
namespace {

constexpr int kByte = TINYGLTF_COMPONENT_TYPE_BYTE, kUByte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
              kShort = TINYGLTF_COMPONENT_TYPE_SHORT, kUShort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
              kUInt = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT;
constexpr std::int32_t kFloatRegionLimit = 1 << 24;  // integers a float holds exactly

std::string item(const std::string& array, std::uint64_t i) { return array + "[" + std::to_string(i) + "]"; }
std::string str(std::uint64_t v) { return std::to_string(v); }

std::string component_name(int type) {
  switch (type) {
    case kByte: return "BYTE";
    case kUByte: return "UNSIGNED_BYTE";
    case kShort: return "SHORT";
    case kUShort: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT: return "INT";
    case kUInt: return "UNSIGNED_INT";
    case kFloat: return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: return "DOUBLE";
    default: return "unknown";
  }
}

std::string type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "unknown";
  }
}

template <class T>
double load_as(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return double(v);
}

double load(const unsigned char* p, int type) {
  switch (type) {
    case kByte: return load_as<std::int8_t>(p);
    case kUByte: return load_as<std::uint8_t>(p);
    case kShort: return load_as<std::int16_t>(p);
    case kUShort: return load_as<std::uint16_t>(p);
    case kUInt: return load_as<std::uint32_t>(p);
    case kFloat: return load_as<float>(p);
    default: return 0;
  }
}

// A checked accessor: `count` elements, `stride` bytes apart.
struct View {
  const unsigned char* data = nullptr;
  std::uint64_t count = 0, stride = 0, index = 0, component_size = 0;
  int type = 0;
  double get(std::uint64_t i, unsigned component) const { return load(data + i * stride + component * component_size, type); }
};

// accessors[i] of `file` for a use (e.g. "meshes[0].primitives[1].attributes.POSITION"); its
// bufferView is present and in range (gltf_model.cpp), its bytes are checked here.
View checked_accessor(const tinygltf::Model& model, const std::string& file, int i, const std::string& use, int type,
                      std::initializer_list<int> components) {
  const auto fail = [&](const std::string& message) { throw InputError(file + ": " + message); };
  const tinygltf::Accessor& a = model.accessors[std::size_t(i)];
  const std::string where = item("accessors", std::uint64_t(i));
  bool allowed = false;
  std::string names;
  for (int c : components) {
    allowed |= c == a.componentType;
    names += (names.empty() ? "" : ", ") + component_name(c);
  }
  if (!allowed)
    fail(where + ".componentType " + str(std::uint64_t(a.componentType)) + " (" + component_name(a.componentType) +
         ") is not read for " + use + " (" + names + ")");
  if (a.type != type) fail(where + ".type is '" + type_name(a.type) + "', not " + type_name(type) + " (" + use + ")");
  const std::string view_name = item("bufferViews", std::uint64_t(a.bufferView));
  const tinygltf::BufferView& bv = model.bufferViews[std::size_t(a.bufferView)];
  const std::vector<unsigned char>& data = model.buffers[std::size_t(bv.buffer)].data;
  // gltf_model.cpp checked this against the declared byteLength; here it guards the bytes loaded.
  if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
    fail(view_name + ": byteOffset " + str(bv.byteOffset) + " + byteLength " + str(bv.byteLength) + " exceeds buffers[" +
         str(std::uint64_t(bv.buffer)) + "] (" + str(data.size()) + " bytes)");
  const auto component_size = std::uint64_t(tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType)));
  const std::uint64_t element_size = component_size * std::uint64_t(tinygltf::GetNumComponentsInType(std::uint32_t(a.type)));
  const std::uint64_t stride = bv.byteStride ? bv.byteStride : element_size;
  if (stride < element_size)
    fail(view_name + ".byteStride " + str(stride) + " is smaller than the " + str(element_size) + "-byte elements of " +
         where);
  const std::uint64_t count = a.count, offset = a.byteOffset, length = bv.byteLength;
  if (count > 0 && (offset > length || element_size > length - offset || count - 1 > (length - offset - element_size) / stride))
    fail(where + ".count " + str(count) + " exceeds " + view_name + " (byteLength " + str(length) + ", accessor byteOffset " +
         str(offset) + ", stride " + str(stride) + ", " + str(element_size) + "-byte elements)");
  View r;
  r.data = data.data() + bv.byteOffset + (count > 0 ? offset : 0);
  r.count = count;
  r.stride = stride;
  r.type = a.componentType;
  r.component_size = component_size;
  r.index = std::uint64_t(i);
  return r;
}

class MeshBuilder {
 public:
  MeshBuilder(const tinygltf::Model& model, std::string file) : model_(model), file_(std::move(file)) {}

  Mesh build() {
    if (model_.scenes.empty()) {
      for (std::size_t m = 0; m < model_.meshes.size(); ++m) add_mesh(m, glm::dmat4(1.0));
    } else {
      walk_scene(std::size_t(std::max(model_.defaultScene, 0)));
    }
    if (!normals_) {
      if (some_normals_) log::warn(file_, ": normals dropped: not every primitive has NORMAL");
      std::vector<float>().swap(mesh_.normals);
    }
    if (!regions_) {
      if (some_regions_) log::warn(file_, ": regions dropped: not every primitive has _REGION");
      std::vector<std::int32_t>().swap(mesh_.regions);
    }
    mesh_.validate(file_);
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { throw InputError(file_ + ": " + message); }

  View accessor(int i, const std::string& use, int type, std::initializer_list<int> components) const {
    return checked_accessor(model_, file_, i, use, type, components);
  }

  glm::dmat4 local_transform(const tinygltf::Node& node, const std::string& where) const {
    if (node.matrix.size() == 16) {
      glm::dmat4 r;
      for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r[c][row] = node.matrix[std::size_t(4 * c + row)];
      return r;
    }
    glm::dmat4 r(1.0);
    if (node.translation.size() == 3) r[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
    if (node.rotation.size() == 4) {
      const auto& q = node.rotation;
      const glm::dquat rotation(q[3], q[0], q[1], q[2]);
      const double length = glm::length(rotation);
      if (!(length > 1e-12) || !std::isfinite(length)) fail(where + ".rotation is not a unit quaternion");
      r = r * glm::dmat4(glm::mat3_cast(rotation / length));
    }
    if (node.scale.size() == 3) {
      const auto& s = node.scale;
      r = r * glm::dmat4(glm::dmat3(glm::dvec3(s[0], 0, 0), glm::dvec3(0, s[1], 0), glm::dvec3(0, 0, s[2])));
    }
    return r;
  }

  void walk_scene(std::size_t s) {
    const std::string where = item("scenes", s);
    std::vector<char> seen(model_.nodes.size(), 0);
    struct Pending {
      std::size_t node;
      glm::dmat4 parent;
    };
    std::vector<Pending> stack;
    auto push = [&](const std::vector<int>& nodes, const glm::dmat4& m) {
      for (std::size_t k = nodes.size(); k-- > 0;) stack.push_back({std::size_t(nodes[k]), m});
    };
    push(model_.scenes[s].nodes, glm::dmat4(1.0));
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      const std::string name = item("nodes", p.node);
      if (seen[p.node]) fail(name + " is reached twice from " + where + " (the node hierarchy must be a tree)");
      seen[p.node] = 1;
      const tinygltf::Node& node = model_.nodes[p.node];
      const glm::dmat4 world = p.parent * local_transform(node, name);
      if (node.mesh >= 0) add_mesh(std::size_t(node.mesh), world);
      push(node.children, world);
    }
  }

  void add_mesh(std::size_t m, const glm::dmat4& world) {
    const std::string where = item("meshes", m) + ".primitives";
    const auto& primitives = model_.meshes[m].primitives;
    for (std::size_t k = 0; k < primitives.size(); ++k) add_primitive(primitives[k], item(where, k), world);
  }

  void add_primitive(const tinygltf::Primitive& p, const std::string& where, const glm::dmat4& world) {
    const int mode = p.mode;
    if (mode >= 1 && mode <= 3) {
      log::warn(file_, ": ", where, " skipped: mode ", mode, " (lines) is not read");
      return;
    }
    const std::string attr = where + ".attributes";
    const auto attribute = [&](const char* name) -> std::optional<int> {
      const auto it = p.attributes.find(name);
      return it == p.attributes.end() ? std::nullopt : std::optional(it->second);
    };
    const auto position = attribute("POSITION");
    if (!position) {
      log::warn(file_, ": ", where, " skipped: it has no POSITION");
      return;
    }
    const View pos = accessor(*position, attr + ".POSITION", TINYGLTF_TYPE_VEC3, {kFloat});
    const std::uint64_t base = mesh_.vertex_count();
    if (pos.count > 0xFFFFFFFFull - base) fail(attr + ".POSITION: the merged mesh would exceed 2^32 vertices");

    const bool identity = world == glm::dmat4(1.0);
    const glm::dmat3 linear(world);
    const double det = glm::determinant(linear);
    // Normals go through the inverse transpose: the cofactor matrix, signed so it keeps orientation.
    const glm::dmat3 cofactor = (det < 0 ? -1.0 : 1.0) * glm::dmat3(glm::cross(linear[1], linear[2]),
                                                                   glm::cross(linear[2], linear[0]),
                                                                   glm::cross(linear[0], linear[1]));
    auto read_vec3 = [&](const View& v, std::uint64_t i, const std::string& use) {
      glm::dvec3 x(v.get(i, 0), v.get(i, 1), v.get(i, 2));
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(x[c]))
          fail(item("accessors", v.index) + " element " + str(i) + " (" + use + ") is " + std::to_string(x[c]) +
               ": NaN and Inf are not accepted");
      return x;
    };

    mesh_.positions.reserve(mesh_.positions.size() + 3 * pos.count);
    for (std::uint64_t i = 0; i < pos.count; ++i) {
      glm::dvec3 x = read_vec3(pos, i, attr + ".POSITION");
      if (!identity) x = glm::dvec3(world * glm::dvec4(x, 1.0));
      for (int c = 0; c < 3; ++c) {
        const float f = float(x[c]);
        if (!std::isfinite(f)) fail(attr + ".POSITION element " + str(i) + " is not finite once transformed by its node");
        mesh_.positions.push_back(f);
      }
    }

    if (const auto normal = attribute("NORMAL"); !normal) {
      normals_ = false;
    } else {
      const View nrm = accessor(*normal, attr + ".NORMAL", TINYGLTF_TYPE_VEC3, {kFloat});
      if (nrm.count != pos.count)
        fail(item("accessors", nrm.index) + ".count " + str(nrm.count) + " (" + attr + ".NORMAL) differs from POSITION's " +
             str(pos.count));
      some_normals_ = true;
      if (normals_) {
        mesh_.normals.reserve(mesh_.normals.size() + 3 * nrm.count);
        for (std::uint64_t i = 0; i < nrm.count; ++i) {
          glm::dvec3 n = read_vec3(nrm, i, attr + ".NORMAL");
          if (!identity) {
            n = cofactor * n;
            const double length = glm::length(n);
            if (length > 0 && std::isfinite(length)) n /= length;
            else n = glm::dvec3(0.0);
          }
          for (int c = 0; c < 3; ++c) mesh_.normals.push_back(float(n[c]));
        }
      }
    }

    if (const auto region = attribute("_REGION"); !region) {
      regions_ = false;
    } else {
      const View reg = accessor(*region, attr + "._REGION", TINYGLTF_TYPE_SCALAR, {kFloat, kByte, kUByte, kShort, kUShort, kUInt});
      if (reg.count != pos.count)
        fail(item("accessors", reg.index) + ".count " + str(reg.count) + " (" + attr + "._REGION) differs from POSITION's " +
             str(pos.count));
      some_regions_ = true;
      if (regions_) {
        mesh_.regions.reserve(mesh_.regions.size() + reg.count);
        for (std::uint64_t i = 0; i < reg.count; ++i) {
          const double r = reg.get(i, 0);
          if (!(r >= -2147483648.0 && r <= 2147483647.0) || r != std::floor(r))
            fail(item("accessors", reg.index) + " element " + str(i) + " (" + attr + "._REGION) is " + std::to_string(r) +
                 ", not an integer region");
          mesh_.regions.push_back(std::int32_t(r));
        }
      }
    }

    if (mode == TINYGLTF_MODE_POINTS) return;  // vertices without faces
    std::optional<View> indices;
    std::string count_name = item("accessors", pos.index) + ".count";
    if (p.indices >= 0) {
      indices = accessor(p.indices, where + ".indices", TINYGLTF_TYPE_SCALAR, {kUByte, kUShort, kUInt});
      count_name = item("accessors", indices->index) + ".count";
    }
    const std::uint64_t n = indices ? indices->count : pos.count;
    auto corner = [&](std::uint64_t k) {
      if (!indices) return std::uint32_t(base + k);
      const double v = indices->get(k, 0);
      if (v >= double(pos.count))
        fail(item("accessors", indices->index) + " element " + str(k) + " (" + where + ".indices) is vertex " +
             str(std::uint64_t(v)) + " but the primitive has " + str(pos.count) + " vertices");
      return std::uint32_t(base + std::uint64_t(v));
    };
    const bool flip = det < 0;  // a mirroring transform turns the winding around
    auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      if (flip) std::swap(b, c);
      mesh_.triangles.insert(mesh_.triangles.end(), {a, b, c});
    };
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (n % 3) fail(count_name + " " + str(n) + " (" + where + ", TRIANGLES) is not a multiple of 3");
      mesh_.triangles.reserve(mesh_.triangles.size() + n);
      for (std::uint64_t k = 0; k < n; k += 3) add(corner(k), corner(k + 1), corner(k + 2));
    } else if (n >= 3) {
      mesh_.triangles.reserve(mesh_.triangles.size() + 3 * (n - 2));
      for (std::uint64_t k = 0; k + 2 < n; ++k) {
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) add(corner(k), corner(k + 1 + k % 2), corner(k + 2 - k % 2));
        else add(corner(k + 1), corner(k + 2), corner(0));  // TRIANGLE_FAN
      }
    }
  }

  const tinygltf::Model& model_;
  std::string file_;
  Mesh mesh_;
  bool normals_ = true, regions_ = true, some_normals_ = false, some_regions_ = false;
};

}  // namespace

Skeleton read_skeleton_gltf(const std::filesystem::path& path) {
  const std::string where = path.string();
  const tinygltf::Model model = load_gltf_model(path);
  if (model.skins.empty()) throw InputError(where + ": has no skin (skins[] is empty)");
  const tinygltf::Skin& skin = model.skins[0];
  Skeleton s;
  std::vector<int> joint_of_node(model.nodes.size(), -1);
  for (std::size_t j = 0; j < skin.joints.size(); ++j) {
    const int node = skin.joints[j];
    if (node < 0 || std::size_t(node) >= model.nodes.size()) throw InputError(where + ": skins[0].joints[" + std::to_string(j) + "] is not a node");
    joint_of_node[std::size_t(node)] = int(j);
  }
  s.parents.assign(skin.joints.size(), -1);
  std::vector<glm::vec3> local(skin.joints.size(), glm::vec3(0));
  for (std::size_t n = 0; n < model.nodes.size(); ++n)
    for (int child : model.nodes[n].children)
      if (child >= 0 && std::size_t(child) < model.nodes.size() && joint_of_node[std::size_t(child)] >= 0)
        s.parents[std::size_t(joint_of_node[std::size_t(child)])] = joint_of_node[n];
  for (std::size_t j = 0; j < skin.joints.size(); ++j) {
    const tinygltf::Node& node = model.nodes[std::size_t(skin.joints[j])];
    s.joint_names.push_back(node.name);
    if (node.translation.size() == 3) local[j] = glm::vec3(node.translation[0], node.translation[1], node.translation[2]);
    if (s.parents[j] >= std::int32_t(j)) throw InputError(where + ": joint " + std::to_string(j) + " comes before its parent");
    s.joint_positions.push_back(local[j] + (s.parents[j] < 0 ? glm::vec3(0) : s.joint_positions[std::size_t(s.parents[j])]));
  }
  for (std::size_t m = 0; m < model.meshes.size(); ++m)
    for (std::size_t k = 0; k < model.meshes[m].primitives.size(); ++k) {
      const tinygltf::Primitive& p = model.meshes[m].primitives[k];
      if (p.mode >= 1 && p.mode <= 3) continue;  // lines: not read (gltf_model.cpp leaves them unchecked)
      const auto joints = p.attributes.find("JOINTS_0"), weights = p.attributes.find("WEIGHTS_0");
      if (joints == p.attributes.end() || weights == p.attributes.end()) continue;
      const std::string attr = item(item("meshes", m) + ".primitives", k) + ".attributes.";
      const View j = checked_accessor(model, where, joints->second, attr + "JOINTS_0", TINYGLTF_TYPE_VEC4, {kUByte, kUShort});
      const View w = checked_accessor(model, where, weights->second, attr + "WEIGHTS_0", TINYGLTF_TYPE_VEC4, {kFloat});
      if (j.count != w.count)
        throw InputError(where + ": " + attr + "JOINTS_0 has " + str(j.count) + " elements, WEIGHTS_0 " + str(w.count));
      // Both lie inside their buffers, so the counts are bounded by the file's size.
      s.skin_joints.resize(kJointInfluences * j.count);
      s.skin_weights.resize(kJointInfluences * w.count);
      for (std::uint64_t v = 0; v < j.count; ++v)
        for (unsigned c = 0; c < kJointInfluences; ++c) {
          s.skin_joints[kJointInfluences * v + c] = std::uint16_t(j.get(v, c));
          s.skin_weights[kJointInfluences * v + c] = float(w.get(v, c));
        }
      s.validate(where, std::size_t(w.count));
      return s;
    }
  throw InputError(where + ": no primitive has JOINTS_0 and WEIGHTS_0");
}

Mesh read_mesh_gltf(const std::filesystem::path& path) {
  const tinygltf::Model model = load_gltf_model(path);
  return MeshBuilder(model, path.string()).build();
}

void write_mesh_glb(const std::filesystem::path& path, const Mesh& m, const Skeleton* skeleton, FileFrame frame,
                    std::span<const float> vertex_colors) {
  const std::string where = path.string();
  m.validate(where);
  if (!vertex_colors.empty() && vertex_colors.size() != 3 * m.vertex_count())
    throw InputError(where + ": " + std::to_string(vertex_colors.size() / 3) + " vertex colours for " + std::to_string(m.vertex_count()) + " vertices");
  for (const float c : vertex_colors)
    if (!(c >= 0.f && c <= 1.f)) throw InputError(where + ": a vertex colour of " + std::to_string(c) + " (glTF's COLOR_0 lies in [0, 1])");
  if (skeleton) skeleton->validate(where, m.vertex_count());
  for (std::size_t v = 0; v < m.regions.size(); ++v)
    if (m.regions[v] > kFloatRegionLimit || m.regions[v] < -kFloatRegionLimit)
      throw InputError(where + ": region " + std::to_string(m.regions[v]) + " of vertex " + std::to_string(v) +
                       " is beyond +-2^24, which the FLOAT _REGION attribute cannot hold exactly");
  const std::uint64_t n = m.vertex_count(), corners = m.triangles.size();
  const std::uint64_t bin = 4 * (3 * n + m.normals.size() + m.regions.size() + corners + vertex_colors.size()) +
                            (skeleton ? 24 * n + 64 * skeleton->joint_count() : 0);
  if (bin > 0xFFFFFFFFull - 65536)  // the JSON of one mesh needs far less than the 64 KiB kept for it
    throw InputError(where + ": the mesh needs " + std::to_string(bin) + " bytes, beyond the 4 GiB a GLB can hold");

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "nf_gpu; " + std::string(frame_marker(frame));
  if (n > 0) {  // an empty mesh: no scene at all (tinygltf would write an empty scene as null)
    tinygltf::Buffer& buffer = model.buffers.emplace_back();
    buffer.data.reserve(bin);
    auto add = [&](const void* data, std::uint64_t count, int component, int type, int target) {
      const std::uint64_t bytes = count * std::uint64_t(tinygltf::GetNumComponentsInType(std::uint32_t(type))) *
                                  std::uint64_t(tinygltf::GetComponentSizeInBytes(std::uint32_t(component)));
      tinygltf::BufferView& view = model.bufferViews.emplace_back();
      view.buffer = 0;
      view.byteOffset = buffer.data.size();
      view.byteLength = bytes;
      if (target) view.target = target;
      const auto* p = static_cast<const unsigned char*>(data);
      buffer.data.insert(buffer.data.end(), p, p + bytes);
      tinygltf::Accessor& a = model.accessors.emplace_back();
      a.bufferView = int(model.bufferViews.size() - 1);
      a.componentType = component;
      a.count = count;
      a.type = type;
      return int(model.accessors.size() - 1);
    };
    tinygltf::Primitive primitive;
    primitive.attributes["POSITION"] = add(m.positions.data(), n, kFloat, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
    tinygltf::Accessor& position = model.accessors.back();
    position.minValues.assign(m.positions.begin(), m.positions.begin() + 3);
    position.maxValues = position.minValues;
    for (std::uint64_t v = 0; v < n; ++v)
      for (std::size_t c = 0; c < 3; ++c) {
        position.minValues[c] = std::min<double>(position.minValues[c], m.positions[3 * v + c]);
        position.maxValues[c] = std::max<double>(position.maxValues[c], m.positions[3 * v + c]);
      }
    if (!m.normals.empty())
      primitive.attributes["NORMAL"] = add(m.normals.data(), n, kFloat, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (!m.regions.empty()) {
      const std::vector<float> regions(m.regions.begin(), m.regions.end());
      primitive.attributes["_REGION"] = add(regions.data(), n, kFloat, TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
    if (!vertex_colors.empty())
      primitive.attributes["COLOR_0"] = add(vertex_colors.data(), n, kFloat, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
    primitive.mode = corners ? TINYGLTF_MODE_TRIANGLES : TINYGLTF_MODE_POINTS;
    if (corners)
      primitive.indices = add(m.triangles.data(), corners, kUInt, TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    if (skeleton) {
      primitive.attributes["JOINTS_0"] = add(skeleton->skin_joints.data(), n, kUShort, TINYGLTF_TYPE_VEC4, TINYGLTF_TARGET_ARRAY_BUFFER);
      primitive.attributes["WEIGHTS_0"] = add(skeleton->skin_weights.data(), n, kFloat, TINYGLTF_TYPE_VEC4, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
    model.meshes.emplace_back().primitives.push_back(std::move(primitive));
    model.nodes.emplace_back().mesh = 0;
    model.scenes.emplace_back().nodes = {0};
    model.defaultScene = 0;
    if (skeleton) {  // joint nodes 1..J, translations relative to the parent; the skin
      const std::size_t J = skeleton->joint_count();
      std::vector<float> inverse_bind(16 * J, 0.f);
      tinygltf::Skin& skin = model.skins.emplace_back();
      skin.name = "body";
      for (std::size_t j = 0; j < J; ++j) {
        tinygltf::Node& node = model.nodes.emplace_back();
        node.name = skeleton->joint_names[j];
        const int parent = skeleton->parents[j];
        const glm::vec3 at = skeleton->joint_positions[j] - (parent < 0 ? glm::vec3(0) : skeleton->joint_positions[std::size_t(parent)]);
        node.translation = {at.x, at.y, at.z};
        if (parent < 0) model.scenes[0].nodes.push_back(int(1 + j));
        else model.nodes[std::size_t(1 + parent)].children.push_back(int(1 + j));
        skin.joints.push_back(int(1 + j));
        float* ib = &inverse_bind[16 * j];  // column-major translate(-position)
        ib[0] = ib[5] = ib[10] = ib[15] = 1.f;
        ib[12] = -skeleton->joint_positions[j].x, ib[13] = -skeleton->joint_positions[j].y, ib[14] = -skeleton->joint_positions[j].z;
      }
      skin.inverseBindMatrices = add(inverse_bind.data(), J, kFloat, TINYGLTF_TYPE_MAT4, 0);
      model.nodes[0].skin = 0;
      model.nodes[0].name = "body";
    }
  }
  write_file_atomic(path, [&](std::ostream& out) {
    tinygltf::TinyGLTF gltf;
    gltf.WriteGltfSceneToStream(&model, out, false, true);  // GLB: 4-byte aligned chunks, BIN padded with NULs
  });
}

}  // namespace nf::io
