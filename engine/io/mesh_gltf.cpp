// Meshes as glTF 2.0 (.glb, .gltf), hand-written on nlohmann::json; mesh.hpp lists what is read
// and what is refused. Every count, offset, stride and index taken from the file is checked, with
// overflow-safe arithmetic, against the bytes that hold it before anything is read, so a malformed
// file ends in an InputError naming the file and the field.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <initializer_list>
#include <optional>
#include <span>
#include <string_view>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/atomic_file.hpp"
#include "engine/core/json.hpp"
#include "engine/core/log.hpp"
#include "engine/io/binary_io.hpp"
#include "engine/io/mesh.hpp"

namespace nf::io {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr std::uint64_t kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123, kUInt = 5125, kFloat = 5126;
constexpr std::uint64_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr std::int32_t kFloatRegionLimit = 1 << 24;  // integers a float holds exactly

std::string item(const std::string& array, std::uint64_t i) { return array + "[" + std::to_string(i) + "]"; }
std::string str(std::uint64_t v) { return std::to_string(v); }

std::uint64_t component_size(std::uint64_t type) {
  switch (type) {
    case kByte: case kUByte: return 1;
    case kShort: case kUShort: return 2;
    case kUInt: case kFloat: return 4;
    default: return 0;
  }
}

std::string component_name(std::uint64_t type) {
  switch (type) {
    case kByte: return "BYTE";
    case kUByte: return "UNSIGNED_BYTE";
    case kShort: return "SHORT";
    case kUShort: return "UNSIGNED_SHORT";
    case kUInt: return "UNSIGNED_INT";
    case kFloat: return "FLOAT";
    default: return "unknown";
  }
}

template <class T>
double load_as(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return double(v);
}

double load(const char* p, std::uint64_t type) {
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

// A JSON value for an error message, never long and never recursive.
std::string describe(const json& j) {
  if (j.is_string()) {
    const auto& s = j.get_ref<const std::string&>();
    return "'" + (s.size() > 40 ? s.substr(0, 40) + "..." : s) + "'";
  }
  if (j.is_primitive()) return j.dump();
  return std::string("an ") + j.type_name();
}

int sextet(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+' || c == '-') return 62;
  if (c == '/' || c == '_') return 63;
  return -1;
}

std::optional<std::vector<char>> decode_base64(std::string_view s) {
  std::vector<char> out;
  out.reserve(s.size() / 4 * 3 + 3);
  std::uint32_t bits = 0;
  int held = 0;
  std::size_t i = 0;
  for (; i < s.size() && s[i] != '='; ++i) {
    const int v = sextet(s[i]);
    if (v < 0) return std::nullopt;
    bits = ((bits << 6) | std::uint32_t(v)) & 0xFFFFFF;
    held += 6;
    if (held >= 8) {
      held -= 8;
      out.push_back(char((bits >> held) & 0xFF));
    }
  }
  for (; i < s.size(); ++i)
    if (s[i] != '=') return std::nullopt;
  return out;
}

std::optional<std::string> percent_decode(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out.push_back(s[i]);
      continue;
    }
    auto hex = [](char c) {
      if (c >= '0' && c <= '9') return c - '0';
      if (c >= 'a' && c <= 'f') return c - 'a' + 10;
      if (c >= 'A' && c <= 'F') return c - 'A' + 10;
      return -1;
    };
    if (i + 2 >= s.size()) return std::nullopt;
    const int hi = hex(s[i + 1]), lo = hex(s[i + 2]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out.push_back(char(hi * 16 + lo));
    i += 2;
  }
  return out;
}

// A checked accessor: `count` elements of `width` components, `stride` bytes apart.
struct View {
  const char* data = nullptr;
  std::uint64_t count = 0, stride = 0, type = 0, index = 0;
  double get(std::uint64_t i, unsigned component) const {
    return load(data + i * stride + component * component_size(type), type);
  }
};

class GltfReader {
 public:
  explicit GltfReader(const fs::path& path) : path_(path), file_(path.string()) {}

  Mesh read() {
    bytes_ = read_file_bytes(path_);
    std::uint32_t magic = 0;
    if (bytes_.size() >= 4) std::memcpy(&magic, bytes_.data(), 4);
    if (magic == kGlbMagic || path_.extension() == ".glb") {
      parse_glb();
    } else {
      parse_json(bytes_.data(), bytes_.size(), "JSON");
      std::vector<char>().swap(bytes_);  // the text is parsed: do not hold it twice
    }
    check_header();
    buffers_.resize(top("buffers").size());

    const json& scenes = top("scenes");
    if (scenes.empty()) {
      for (std::uint64_t m = 0; m < top("meshes").size(); ++m) add_mesh(m, glm::dmat4(1.0), "meshes");
    } else {
      walk_scene(number(root_, "scene", "").value_or(0));
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

  static std::string field(const std::string& where, const char* key) {
    return where.empty() ? std::string(key) : where + "." + key;
  }

  void parse_json(const char* data, std::size_t size, const char* what) {
    // Tolerate the trailing NULs some writers pad the JSON chunk with.
    while (size > 0 && data[size - 1] == '\0') --size;
    try {
      root_ = json::parse(data, data + size);
    } catch (const json::exception& e) {
      fail(std::string(what) + " is malformed: " + e.what());
    }
    if (!root_.is_object()) fail(std::string(what) + " is " + describe(root_) + ", not an object");
  }

  std::uint32_t u32_at(std::size_t offset) const {
    std::uint32_t v;
    std::memcpy(&v, bytes_.data() + offset, 4);
    return v;
  }

  void parse_glb() {
    const std::uint64_t size = bytes_.size();
    if (size < 12) fail("the file has " + str(size) + " bytes, fewer than the 12-byte GLB header (truncated?)");
    if (u32_at(0) != kGlbMagic) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", u32_at(0));
      fail(std::string("GLB magic is ") + hex + ", not 'glTF' (0x46546c67): not a binary glTF file");
    }
    if (u32_at(4) != 2) fail("GLB header version " + str(u32_at(4)) + " is not 2");
    if (u32_at(8) != size)
      fail("GLB header length " + str(u32_at(8)) + " disagrees with the file size " + str(size) + " (truncated?)");
    std::uint64_t offset = 12;
    for (int chunk = 0; offset < size; ++chunk) {
      const std::string name = "GLB chunk " + std::to_string(chunk);
      if (size - offset < 8)
        fail(name + " header at byte " + str(offset) + " needs 8 bytes, the file has " + str(size - offset) + " left");
      const std::uint64_t length = u32_at(offset), type = u32_at(offset + 4);
      if (length > size - offset - 8)
        fail(name + " length " + str(length) + " at byte " + str(offset) + " runs past the end of the file (" +
             str(size) + " bytes)");
      const char* data = bytes_.data() + offset + 8;
      if (chunk == 0) {
        if (type != kChunkJson) fail(name + " is not the JSON chunk (type " + str(type) + ")");
        parse_json(data, length, "the GLB JSON chunk");
      } else if (chunk == 1 && type == kChunkBin) {
        bin_ = std::span<const char>(data, length);
        has_bin_ = true;
      }  // other chunks: ignored, as the spec asks
      offset += 8 + length;
    }
    if (root_.is_null()) fail("GLB has no JSON chunk");
  }

  void check_header() {
    const auto asset = root_.find("asset");
    if (asset == root_.end() || !asset->is_object()) fail("asset is missing (not a glTF 2.0 file?)");
    const auto version = asset->find("version");
    if (version == asset->end() || !version->is_string() || version->get_ref<const std::string&>().rfind("2.", 0) != 0)
      fail("asset.version is " + (version == asset->end() ? std::string("missing") : describe(*version)) +
           ", not 2.x (only glTF 2.0 is read)");
    const json& required = top("extensionsRequired");
    for (std::uint64_t i = 0; i < required.size(); ++i) {
      if (!required[i].is_string()) continue;
      const auto& e = required[i].get_ref<const std::string&>();
      if (e == "KHR_draco_mesh_compression" || e == "EXT_meshopt_compression" || e == "KHR_mesh_quantization")
        fail(item("extensionsRequired", i) + " is " + e + ": compressed or quantized geometry is not read");
    }
  }

  // A top-level array (empty when absent).
  const json& top(const char* name) const {
    static const json empty = json::array();
    const auto it = root_.find(name);
    if (it == root_.end()) return empty;
    if (!it->is_array()) fail(std::string(name) + " is " + describe(*it) + ", not an array");
    return *it;
  }

  const json& element(const char* array, std::uint64_t i, const std::string& referrer) const {
    const json& a = top(array);
    if (i >= a.size())
      fail(referrer + " refers to " + item(array, i) + " but the file has " + str(a.size()) + " " + array);
    if (!a[i].is_object()) fail(item(array, i) + " is " + describe(a[i]) + ", not an object");
    return a[i];
  }

  std::optional<std::uint64_t> number(const json& object, const char* key, const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) return std::nullopt;
    if (!it->is_number_unsigned()) fail(field(where, key) + " is " + describe(*it) + ", not a non-negative integer");
    return it->get<std::uint64_t>();
  }

  std::uint64_t required(const json& object, const char* key, const std::string& where) const {
    const auto v = number(object, key, where);
    if (!v) fail(field(where, key) + " is missing");
    return *v;
  }

  // An index into the top-level `array`, checked against its size.
  std::uint64_t reference(const json& object, const char* key, const std::string& where, const char* array) const {
    const std::uint64_t i = required(object, key, where);
    if (i >= top(array).size())
      fail(field(where, key) + " is " + str(i) + " but the file has " + str(top(array).size()) + " " + array);
    return i;
  }

  std::vector<double> numbers(const json& j, std::size_t n, const std::string& name) const {
    if (!j.is_array() || j.size() != n) fail(name + " is not an array of " + str(n) + " numbers");
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (!j[i].is_number()) fail(item(name, i) + " is " + describe(j[i]) + ", not a number");
      v[i] = j[i].get<double>();
      if (!std::isfinite(v[i])) fail(item(name, i) + " is not finite");
    }
    return v;
  }

  std::span<const char> buffer(std::uint64_t i, const std::string& referrer) {
    const json& b = element("buffers", i, referrer);
    if (buffers_[i]) return *buffers_[i];
    const std::string where = item("buffers", i);
    const std::uint64_t length = required(b, "byteLength", where);
    const auto uri = b.find("uri");
    std::span<const char> data;
    if (uri == b.end()) {
      if (i != 0 || !has_bin_) fail(where + " has no uri and " + (i != 0 ? "is not the first buffer" : "the file has no GLB BIN chunk"));
      if (length > bin_.size())
        fail(where + ".byteLength " + str(length) + " exceeds the GLB BIN chunk (" + str(bin_.size()) + " bytes)");
      data = bin_.first(length);
    } else {
      if (!uri->is_string()) fail(where + ".uri is " + describe(*uri) + ", not a string");
      storage_.push_back(load_uri(uri->get_ref<const std::string&>(), length, where));
      data = std::span<const char>(storage_.back().data(), storage_.back().size());
    }
    buffers_[i] = data;
    return data;
  }

  std::vector<char> load_uri(const std::string& uri, std::uint64_t length, const std::string& where) const {
    const std::string name = where + ".uri " + describe(json(uri));
    if (uri.rfind("data:", 0) == 0) {
      const std::size_t comma = uri.find(',');
      if (comma == std::string::npos || comma < 12 || uri.compare(comma - 7, 7, ";base64") != 0)
        fail(name + " is a data: URI without ';base64,' (only base64 data URIs are read)");
      auto bytes = decode_base64(std::string_view(uri).substr(comma + 1));
      if (!bytes) fail(name + ": the base64 data is malformed");
      if (bytes->size() < length)
        fail(where + ".byteLength " + str(length) + " exceeds the " + str(bytes->size()) + " bytes of its data: URI");
      bytes->resize(length);
      return std::move(*bytes);
    }
    const std::size_t colon = uri.find(':'), slash = uri.find('/');
    if (colon != std::string::npos && (slash == std::string::npos || colon < slash))
      fail(name + " is neither a relative file path nor a data: URI (nothing is downloaded)");
    const auto decoded = percent_decode(uri);
    if (!decoded || decoded->empty() || decoded->find('\0') != std::string::npos)
      fail(name + " is not a usable file path (empty, a bad %-escape, or a NUL)");
    const fs::path file = path_.parent_path() / fs::path(*decoded);
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) fail(name + ": " + file.string() + " is missing or not a regular file");
    const std::uint64_t size = fs::file_size(file, ec);
    if (ec) fail(name + ": cannot read " + file.string());
    if (size < length)
      fail(where + ".byteLength " + str(length) + " exceeds " + file.string() + " (" + str(size) + " bytes)");
    std::vector<char> data(length);
    std::ifstream in(file, std::ios::binary);
    if (!in.read(data.data(), std::streamsize(length))) fail(name + ": cannot read " + file.string());
    return data;
  }

  // Checks accessors[i] for a use (e.g. "meshes[0].primitives[1].attributes.POSITION").
  View accessor(std::uint64_t i, const std::string& use, const char* type, unsigned width,
                std::initializer_list<std::uint64_t> components) {
    const json& a = element("accessors", i, use);
    const std::string where = item("accessors", i);
    if (a.contains("sparse")) fail(where + " (" + use + ") is sparse: sparse accessors are not read");
    const std::uint64_t component = required(a, "componentType", where);
    bool allowed = false;
    std::string names;
    for (std::uint64_t c : components) {
      allowed |= c == component;
      names += (names.empty() ? "" : ", ") + component_name(c);
    }
    if (!allowed)
      fail(where + ".componentType " + str(component) + " (" + component_name(component) + ") is not read for " + use +
           " (" + names + ")");
    const auto t = a.find("type");
    if (t == a.end() || !t->is_string() || *t != type)
      fail(where + ".type is " + (t == a.end() ? std::string("missing") : describe(*t)) + ", not " + type + " (" + use +
           ")");
    const std::uint64_t count = required(a, "count", where);
    if (!a.contains("bufferView"))
      fail(where + " (" + use + ") has no bufferView: zero-filled or compressed accessors are not read");
    const std::uint64_t v = reference(a, "bufferView", where, "bufferViews");
    const std::string view_name = item("bufferViews", v);
    const json& bv = element("bufferViews", v, where + ".bufferView");
    const std::uint64_t buffer_index = reference(bv, "buffer", view_name, "buffers");
    const std::span<const char> data = buffer(buffer_index, view_name + ".buffer");
    const std::uint64_t view_offset = number(bv, "byteOffset", view_name).value_or(0);
    const std::uint64_t view_length = required(bv, "byteLength", view_name);
    if (view_offset > data.size() || view_length > data.size() - view_offset)
      fail(view_name + ": byteOffset " + str(view_offset) + " + byteLength " + str(view_length) + " exceeds buffers[" +
           str(buffer_index) + "] (" + str(data.size()) + " bytes)");
    const std::uint64_t element_size = component_size(component) * width;
    const std::uint64_t stride = number(bv, "byteStride", view_name).value_or(element_size);
    if (stride < element_size)
      fail(view_name + ".byteStride " + str(stride) + " is smaller than the " + str(element_size) + "-byte elements of " +
           where);
    const std::uint64_t offset = number(a, "byteOffset", where).value_or(0);
    if (count > 0 && (offset > view_length || element_size > view_length - offset ||
                      count - 1 > (view_length - offset - element_size) / stride))
      fail(where + ".count " + str(count) + " exceeds " + view_name + " (byteLength " + str(view_length) +
           ", accessor byteOffset " + str(offset) + ", stride " + str(stride) + ", " + str(element_size) +
           "-byte elements)");
    View r;
    r.data = data.data() + view_offset + (count > 0 ? offset : 0);
    r.count = count;
    r.stride = stride;
    r.type = component;
    r.index = i;
    return r;
  }

  glm::dmat4 local_transform(const json& node, const std::string& where) const {
    if (const auto m = node.find("matrix"); m != node.end()) {
      const auto v = numbers(*m, 16, where + ".matrix");
      glm::dmat4 r;
      for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r[c][row] = v[std::size_t(4 * c + row)];
      return r;
    }
    glm::dmat4 r(1.0);
    if (const auto t = node.find("translation"); t != node.end()) {
      const auto v = numbers(*t, 3, where + ".translation");
      r[3] = glm::dvec4(v[0], v[1], v[2], 1.0);
    }
    if (const auto q = node.find("rotation"); q != node.end()) {
      const auto v = numbers(*q, 4, where + ".rotation");
      const glm::dquat rotation(v[3], v[0], v[1], v[2]);
      const double length = glm::length(rotation);
      if (!(length > 1e-12) || !std::isfinite(length)) fail(where + ".rotation is not a unit quaternion");
      r = r * glm::dmat4(glm::mat3_cast(rotation / length));
    }
    if (const auto s = node.find("scale"); s != node.end()) {
      const auto v = numbers(*s, 3, where + ".scale");
      r = r * glm::dmat4(glm::dmat3(glm::dvec3(v[0], 0, 0), glm::dvec3(0, v[1], 0), glm::dvec3(0, 0, v[2])));
    }
    return r;
  }

  void walk_scene(std::uint64_t s) {
    const json& scene = element("scenes", s, "scene");
    const std::string where = item("scenes", s);
    const json& nodes = top("nodes");
    std::vector<char> seen(nodes.size(), 0);
    struct Pending {
      std::uint64_t node;
      glm::dmat4 parent;
    };
    std::vector<Pending> stack;
    auto push_children = [&](const json& holder, const char* key, const std::string& holder_name, const glm::dmat4& m) {
      const auto list = holder.find(key);
      if (list == holder.end()) return;
      const std::string name = field(holder_name, key);
      if (!list->is_array()) fail(name + " is " + describe(*list) + ", not an array");
      for (std::size_t k = list->size(); k-- > 0;) {
        const json& entry = (*list)[k];
        if (!entry.is_number_unsigned() || entry.get<std::uint64_t>() >= nodes.size())
          fail(item(name, k) + " is " + describe(entry) + ", not an index below the " + str(nodes.size()) + " nodes");
        stack.push_back({entry.get<std::uint64_t>(), m});
      }
    };
    push_children(scene, "nodes", where, glm::dmat4(1.0));
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      const std::string name = item("nodes", p.node);
      if (seen[p.node]) fail(name + " is reached twice from " + where + " (the node hierarchy must be a tree)");
      seen[p.node] = 1;
      const json& node = element("nodes", p.node, where);
      const glm::dmat4 world = p.parent * local_transform(node, name);
      if (node.contains("mesh")) add_mesh(reference(node, "mesh", name, "meshes"), world, name + ".mesh");
      push_children(node, "children", name, world);
    }
  }

  void add_mesh(std::uint64_t m, const glm::dmat4& world, const std::string& referrer) {
    const json& mesh = element("meshes", m, referrer);
    const std::string where = item("meshes", m) + ".primitives";
    const auto primitives = mesh.find("primitives");
    if (primitives == mesh.end() || !primitives->is_array()) fail(where + " is missing or not an array");
    for (std::size_t k = 0; k < primitives->size(); ++k) add_primitive((*primitives)[k], item(where, k), world);
  }

  void add_primitive(const json& p, const std::string& where, const glm::dmat4& world) {
    if (!p.is_object()) fail(where + " is " + describe(p) + ", not an object");
    const std::uint64_t mode = number(p, "mode", where).value_or(4);
    if (mode > 6) fail(where + ".mode " + str(mode) + " is not a glTF primitive mode (0..6)");
    if (mode >= 1 && mode <= 3) {
      log::warn(file_, ": ", where, " skipped: mode ", mode, " (lines) is not read");
      return;
    }
    const auto attributes = p.find("attributes");
    const std::string attr = where + ".attributes";
    if (attributes == p.end() || !attributes->is_object()) fail(attr + " is missing or not an object");
    if (!attributes->contains("POSITION")) {
      log::warn(file_, ": ", where, " skipped: it has no POSITION");
      return;
    }
    const View pos = accessor(reference(*attributes, "POSITION", attr, "accessors"), attr + ".POSITION", "VEC3", 3, {kFloat});
    const std::uint64_t base = mesh_.vertex_count();
    if (pos.count > 0xFFFFFFFFull - base)
      fail(attr + ".POSITION: the merged mesh would exceed 2^32 vertices");

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

    if (!attributes->contains("NORMAL")) {
      normals_ = false;
    } else {
      const View nrm = accessor(reference(*attributes, "NORMAL", attr, "accessors"), attr + ".NORMAL", "VEC3", 3, {kFloat});
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

    if (!attributes->contains("_REGION")) {
      regions_ = false;
    } else {
      const View reg = accessor(reference(*attributes, "_REGION", attr, "accessors"), attr + "._REGION", "SCALAR", 1,
                                {kFloat, kByte, kUByte, kShort, kUShort, kUInt});
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

    if (mode == 0) return;  // POINTS: vertices without faces
    std::optional<View> indices;
    std::string count_name = item("accessors", pos.index) + ".count";
    if (p.contains("indices")) {
      indices = accessor(reference(p, "indices", where, "accessors"), where + ".indices", "SCALAR", 1, {kUByte, kUShort, kUInt});
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
    if (mode == 4) {
      if (n % 3) fail(count_name + " " + str(n) + " (" + where + ", TRIANGLES) is not a multiple of 3");
      mesh_.triangles.reserve(mesh_.triangles.size() + n);
      for (std::uint64_t k = 0; k < n; k += 3) add(corner(k), corner(k + 1), corner(k + 2));
    } else if (n >= 3) {
      mesh_.triangles.reserve(mesh_.triangles.size() + 3 * (n - 2));
      for (std::uint64_t k = 0; k + 2 < n; ++k) {
        if (mode == 5) add(corner(k), corner(k + 1 + k % 2), corner(k + 2 - k % 2));  // TRIANGLE_STRIP
        else add(corner(k + 1), corner(k + 2), corner(0));                          // TRIANGLE_FAN
      }
    }
  }

  fs::path path_;
  std::string file_;
  std::vector<char> bytes_;  // the whole file while it holds the GLB BIN chunk
  std::span<const char> bin_;
  bool has_bin_ = false;
  json root_;
  std::deque<std::vector<char>> storage_;  // buffers loaded from URIs
  std::vector<std::optional<std::span<const char>>> buffers_;
  Mesh mesh_;
  bool normals_ = true, regions_ = true, some_normals_ = false, some_regions_ = false;
};

void put_u32(std::ostream& out, std::uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); }

}  // namespace

Mesh read_mesh_gltf(const std::filesystem::path& path) {
  try {
    return GltfReader(path).read();
  } catch (const json::exception& e) {  // a JSON shape no check above foresaw
    throw InputError(path.string() + ": malformed glTF JSON: " + e.what());
  }
}

void write_mesh_glb(const std::filesystem::path& path, const Mesh& m) {
  const std::string where = path.string();
  m.validate(where);
  for (std::size_t v = 0; v < m.regions.size(); ++v)
    if (m.regions[v] > kFloatRegionLimit || m.regions[v] < -kFloatRegionLimit)
      throw InputError(where + ": region " + std::to_string(m.regions[v]) + " of vertex " + std::to_string(v) +
                       " is beyond +-2^24, which the FLOAT _REGION attribute cannot hold exactly");
  const std::uint64_t n = m.vertex_count(), corners = m.triangles.size();

  json doc;
  doc["asset"] = json{{"version", "2.0"}, {"generator", "nf_gpu"}};
  doc["scene"] = 0;
  std::uint64_t bin = 0;
  if (n == 0) {
    doc["scenes"] = json::array({json::object()});
  } else {
    json views = json::array(), accessors = json::array();
    auto add = [&](std::uint64_t bytes, std::uint64_t count, std::uint64_t component, const char* type,
                   std::uint64_t target) {
      views.push_back(json{{"buffer", 0}, {"byteOffset", bin}, {"byteLength", bytes}, {"target", target}});
      accessors.push_back(
          json{{"bufferView", views.size() - 1}, {"componentType", component}, {"count", count}, {"type", type}});
      bin += bytes;
      return accessors.size() - 1;
    };
    json attributes;
    attributes["POSITION"] = add(12 * n, n, kFloat, "VEC3", kArrayBuffer);
    std::vector<float> lo(m.positions.begin(), m.positions.begin() + 3), hi = lo;
    for (std::uint64_t v = 0; v < n; ++v)
      for (int c = 0; c < 3; ++c) {
        lo[std::size_t(c)] = std::min(lo[std::size_t(c)], m.positions[3 * v + std::size_t(c)]);
        hi[std::size_t(c)] = std::max(hi[std::size_t(c)], m.positions[3 * v + std::size_t(c)]);
      }
    accessors.back()["min"] = lo;
    accessors.back()["max"] = hi;
    if (!m.normals.empty()) attributes["NORMAL"] = add(12 * n, n, kFloat, "VEC3", kArrayBuffer);
    if (!m.regions.empty()) attributes["_REGION"] = add(4 * n, n, kFloat, "SCALAR", kArrayBuffer);
    json primitive = {{"attributes", attributes}, {"mode", corners ? 4 : 0}};  // no faces: POINTS
    if (corners) primitive["indices"] = add(4 * corners, corners, kUInt, "SCALAR", kElementArrayBuffer);
    doc["scenes"] = json::array({json{{"nodes", json::array({0})}}});
    doc["nodes"] = json::array({json{{"mesh", 0}}});
    doc["meshes"] = json::array({json{{"primitives", json::array({primitive})}}});
    doc["accessors"] = std::move(accessors);
    doc["bufferViews"] = std::move(views);
    doc["buffers"] = json::array({json{{"byteLength", bin}}});
  }
  std::string text = doc.dump();
  text.resize((text.size() + 3) / 4 * 4, ' ');
  const std::uint64_t bin_padded = (bin + 3) / 4 * 4;
  const std::uint64_t total = 12 + 8 + text.size() + (bin ? 8 + bin_padded : 0);
  if (total > 0xFFFFFFFFull)
    throw InputError(where + ": the mesh needs " + std::to_string(total) + " bytes, beyond the 4 GiB a GLB can hold");

  write_file_atomic(path, [&](std::ostream& out) {
    put_u32(out, kGlbMagic);
    put_u32(out, 2);
    put_u32(out, std::uint32_t(total));
    put_u32(out, std::uint32_t(text.size()));
    put_u32(out, kChunkJson);
    out.write(text.data(), std::streamsize(text.size()));
    if (!bin) return;
    put_u32(out, std::uint32_t(bin_padded));
    put_u32(out, kChunkBin);
    write_array(out, m.positions);
    write_array(out, m.normals);
    for (std::int32_t r : m.regions) {
      const float f = float(r);
      out.write(reinterpret_cast<const char*>(&f), 4);
    }
    write_array(out, m.triangles);
    for (std::uint64_t k = bin; k < bin_padded; ++k) out.put('\0');
  });
}

}  // namespace nf::io
