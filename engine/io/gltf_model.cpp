// tinygltf parses the file and loads the buffers (GLB BIN chunk, files beside the .gltf, base64 data:
// URIs). The checks around it exist because tinygltf 2.7.0 names no element in its errors ("'count'
// property is not a positive integer."), reads some wrong types silently as defaults (a string
// "mesh" becomes no mesh, a fractional byteOffset becomes 0) and throws std::out_of_range on an
// empty GLB buffer. So the JSON is parsed once more (nlohmann, as tinygltf does; a small fraction of
// a .glb or of a .gltf with external buffers) and what the mesh reader uses is checked first, with
// errors that name the field.
#include "engine/io/gltf_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <optional>
#include <string_view>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/binary_io.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::io {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr std::size_t kMaxNesting = 256;           // glTF itself nests 6 levels; extras add a few

std::string str(std::uint64_t v) { return std::to_string(v); }
std::string item(const std::string& array, std::uint64_t i) { return array + "[" + str(i) + "]"; }
std::string field(const std::string& where, const std::string& key) { return where.empty() ? key : where + "." + key; }

// What tinygltf's file-system callbacks saw, for the error when a buffer file fails.
struct FileAccess {
  std::string base;     // the .gltf's folder, as handed to tinygltf
  std::string problem;  // why the last file was not found
  std::string path;     // the last file read, and its size
  std::uint64_t size = 0;
};

// tinygltf looks for a buffer beside the .gltf, then in the working directory: only the first is
// the file's own.
bool file_exists(const std::string& path, void* user) {
  auto& access = *static_cast<FileAccess*>(user);
  if (path.compare(0, access.base.size(), access.base) != 0) return false;
  if (path.find('\0') != std::string::npos) {
    access.problem = "the decoded file name holds a NUL character";
    return false;
  }
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return true;
  access.problem = path + " is missing or not a regular file";
  return false;
}

// tinygltf's default expands ~ and $VARIABLES (wordexp): a file name is taken as written.
std::string expand_path(const std::string& path, void*) { return path; }

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  auto& access = *static_cast<FileAccess*>(user);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    access.problem = "cannot read " + path;
    *err = access.problem;
    return false;
  }
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  access.path = path;
  access.size = out->size();
  return true;
}

// Images are not read: the mesh reader needs geometry only.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// How deeply arrays and objects nest in valid JSON text.
std::size_t nesting(std::string_view text) {
  std::size_t depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

std::string first_line(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  return line.size() > 200 ? line.substr(0, 200) + "..." : line;  // tinygltf quotes whole data: URIs
}

class Loader {
 public:
  explicit Loader(const fs::path& path) : path_(path), file_(path.string()) {}

  tinygltf::Model load() {
    std::vector<char> bytes = read_file_bytes(path_);
    std::uint32_t magic = 0;
    if (bytes.size() >= 4) std::memcpy(&magic, bytes.data(), 4);
    glb_ = magic == kGlbMagic || path_.extension() == ".glb";
    std::string_view text(bytes.data(), bytes.size());
    if (glb_) text = check_glb(bytes);
    else if (bytes.size() > 0xFFFFFFFFull) fail("the file is larger than the 4 GiB a glTF reader takes");
    parse(text);
    check_document();
    return run_tinygltf(bytes, text);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { throw InputError(file_ + ": " + message); }

  // ---- the GLB container: tinygltf checks it too, naming no chunk or offset ----

  static std::uint32_t u32(const std::vector<char>& bytes, std::uint64_t offset) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + offset, 4);
    return v;
  }

  // Returns the JSON chunk; notes the BIN chunk's size.
  std::string_view check_glb(std::vector<char>& bytes) {
    const std::uint64_t size = bytes.size();
    if (size < 12) fail("the file has " + str(size) + " bytes, fewer than the 12-byte GLB header (truncated?)");
    if (u32(bytes, 0) != kGlbMagic) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08x", u32(bytes, 0));
      fail(std::string("GLB magic is ") + hex + ", not 'glTF' (0x46546c67): not a binary glTF file");
    }
    if (u32(bytes, 4) != 2) fail("GLB header version " + str(u32(bytes, 4)) + " is not 2");
    if (u32(bytes, 8) != size)
      fail("GLB header length " + str(u32(bytes, 8)) + " disagrees with the file size " + str(size) + " (truncated?)");
    std::string_view json_chunk;
    std::uint64_t offset = 12;
    for (int chunk = 0; offset < size; ++chunk) {
      const std::string name = "GLB chunk " + std::to_string(chunk);
      if (size - offset < 8)
        fail(name + " header at byte " + str(offset) + " needs 8 bytes, the file has " + str(size - offset) + " left");
      const std::uint64_t length = u32(bytes, offset), type = u32(bytes, offset + 4);
      if (length > size - offset - 8)
        fail(name + " length " + str(length) + " at byte " + str(offset) + " runs past the end of the file (" +
             str(size) + " bytes)");
      char* data = bytes.data() + offset + 8;
      if (chunk == 0) {
        if (type != kChunkJson) fail(name + " is not the JSON chunk (type " + str(type) + ")");
        if (length % 4) fail(name + " (JSON) length " + str(length) + " is not a multiple of 4, as chunks must be");
        // Some writers pad the JSON with NULs where the spec asks for spaces.
        for (std::uint64_t k = length; k > 0 && data[k - 1] == '\0'; --k) data[k - 1] = ' ';
        json_chunk = std::string_view(data, length);
      } else if (chunk == 1) {
        if (type != kChunkBin) fail(name + " (type " + str(type) + ") is not the BIN chunk, which must come second");
        if (length == 0 || length % 4) fail(name + " (BIN) length " + str(length) + " is not a positive multiple of 4");
        bin_size_ = length;
      }  // later chunks: ignored, as the spec asks
      offset += 8 + length;
    }
    if (json_chunk.data() == nullptr) fail("GLB has no JSON chunk");
    return json_chunk;
  }

  void parse(std::string_view text) {
    const std::string what = glb_ ? "the GLB JSON chunk" : "JSON";
    try {
      doc_ = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {
      fail(what + " is malformed: " + json_error_text(e));
    }
    if (!doc_.is_object()) fail(what + " is " + describe_json(doc_) + ", not an object");
    // tinygltf copies extras and extensions recursively: deep nesting would overflow the stack.
    if (const std::size_t depth = nesting(text); depth > kMaxNesting)
      fail(what + " nests arrays and objects " + str(depth) + " levels deep, more than the " + str(kMaxNesting) + " read");
  }

  // ---- what the mesh reader uses: types and indices, before tinygltf reads them ----

  void check_document() {
    const auto asset = doc_.find("asset");
    if (asset == doc_.end() || !asset->is_object()) fail("asset is missing (not a glTF 2.0 file?)");
    const auto version = asset->find("version");
    if (version == asset->end() || !version->is_string() || version->get_ref<const std::string&>().rfind("2.", 0) != 0)
      fail("asset.version is " + (version == asset->end() ? std::string("missing") : quoted(*version)) +
           ", not 2.x (only glTF 2.0 is read)");
    const json& extensions = top("extensionsRequired");
    for (std::size_t i = 0; i < extensions.size(); ++i) {
      const std::string e = extensions[i].is_string() ? extensions[i].get<std::string>() : "";
      if (e == "KHR_draco_mesh_compression" || e == "EXT_meshopt_compression" || e == "KHR_mesh_quantization")
        fail(item("extensionsRequired", i) + " is " + e + ": compressed or quantized geometry is not read");
    }
    for (std::size_t i = 0; i < top("buffers").size(); ++i) check_buffer(i);
    for (std::size_t i = 0; i < top("bufferViews").size(); ++i) {
      const json& v = element("bufferViews", i);
      const std::string where = item("bufferViews", i);
      const std::uint64_t buffer = *reference(v, "buffer", where, "buffers", true);
      const std::uint64_t offset = number(v, "byteOffset", where).value_or(0), length = required(v, "byteLength", where);
      // Every view, not only the mesh's: tinygltf hands an image's view to the image loader unchecked.
      const std::uint64_t size = top("buffers")[buffer]["byteLength"].get<std::uint64_t>();
      if (offset > size || length > size - offset)
        fail(where + ": byteOffset " + str(offset) + " + byteLength " + str(length) + " exceeds buffers[" + str(buffer) +
             "] (" + str(size) + " bytes)");
      const auto stride = number(v, "byteStride", where);
      if (stride && (*stride < 4 || *stride > 252 || *stride % 4))
        fail(where + ".byteStride " + str(*stride) + " is not a multiple of 4 from 4 to 252, as glTF requires");
    }
    for (std::size_t i = 0; i < top("accessors").size(); ++i) {
      const json& a = element("accessors", i);
      const std::string where = item("accessors", i);
      reference(a, "bufferView", where, "bufferViews", false);
      number(a, "byteOffset", where);
      const std::uint64_t component = required(a, "componentType", where);
      if (component < 5120 || component > 5130)
        fail(where + ".componentType " + str(component) + " is not a glTF component type (BYTE 5120 to FLOAT 5126)");
      required(a, "count", where);
      const auto type = a.find("type");
      static const std::vector<std::string> types = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
      if (type == a.end() || !type->is_string() ||
          std::find(types.begin(), types.end(), type->get_ref<const std::string&>()) == types.end())
        fail(where + ".type is " + (type == a.end() ? std::string("missing") : quoted(*type)) + ", not a glTF accessor type");
    }
    for (std::size_t m = 0; m < top("meshes").size(); ++m) check_mesh(m);
    for (std::size_t n = 0; n < top("nodes").size(); ++n) {
      const json& node = element("nodes", n);
      const std::string where = item("nodes", n);
      reference(node, "mesh", where, "meshes", false);
      node_list(node, "children", where);
      numbers(node, "matrix", 16, where);
      numbers(node, "translation", 3, where);
      numbers(node, "rotation", 4, where);
      numbers(node, "scale", 3, where);
    }
    for (std::size_t s = 0; s < top("scenes").size(); ++s) node_list(element("scenes", s), "nodes", item("scenes", s));
    number(doc_, "scene", "");
    if (!top("scenes").empty()) reference(doc_, "scene", "", "scenes", false);  // without scenes, unused
  }

  void check_buffer(std::size_t i) {
    const json& b = element("buffers", i);
    const std::string where = item("buffers", i);
    const std::uint64_t length = required(b, "byteLength", where);
    if (length == 0) fail(where + ".byteLength is 0: a glTF buffer holds at least one byte");
    const auto uri = b.find("uri");
    if (uri == b.end()) {
      if (!glb_ || i != 0) fail(where + " has no uri and is not the first buffer of a GLB file");
      if (!bin_size_) fail(where + " has no uri and the file has no GLB BIN chunk");
      if (length > *bin_size_)
        fail(where + ".byteLength " + str(length) + " exceeds the GLB BIN chunk (" + str(*bin_size_) + " bytes)");
      return;
    }
    if (!uri->is_string()) fail(where + ".uri is " + describe_json(*uri) + ", not a string");
    const std::string& s = uri->get_ref<const std::string&>();
    const std::string name = where + ".uri " + quoted(*uri);
    if (s.rfind("data:", 0) == 0) {
      if (!tinygltf::IsDataURI(s))
        fail(name + " is not a base64 data: URI of type application/octet-stream or application/gltf-buffer");
      return;
    }
    const std::size_t colon = s.find(':'), slash = s.find('/');
    if (colon != std::string::npos && (slash == std::string::npos || colon < slash))
      fail(name + " is neither a relative file path nor a data: URI (nothing is downloaded)");
    if (s.empty()) fail(name + " is empty");
  }

  void check_mesh(std::size_t m) {
    const json& mesh = element("meshes", m);
    const std::string where = item("meshes", m) + ".primitives";
    const auto primitives = mesh.find("primitives");
    if (primitives == mesh.end() || !primitives->is_array()) fail(where + " is missing or not an array");
    for (std::size_t k = 0; k < primitives->size(); ++k) {
      const json& p = (*primitives)[k];
      const std::string name = item(where, k);
      if (!p.is_object()) fail(name + " is " + describe_json(p) + ", not an object");
      const std::uint64_t mode = number(p, "mode", name).value_or(4);
      if (mode > 6) fail(name + ".mode " + str(mode) + " is not a glTF primitive mode (0..6)");
      const auto attributes = p.find("attributes");
      const std::string attr = name + ".attributes";
      if (attributes == p.end() || !attributes->is_object()) fail(attr + " is missing or not an object");
      for (const auto& [key, value] : attributes->items()) number(*attributes, key.c_str(), attr);
      if (mode >= 1 && mode <= 3) continue;  // lines: skipped by the reader
      for (const char* key : {"POSITION", "NORMAL", "_REGION", "JOINTS_0", "WEIGHTS_0"})
        if (const auto a = reference(*attributes, key, attr, "accessors", false)) read_accessor(*a, field(attr, key));
      if (const auto a = reference(p, "indices", name, "accessors", false)) read_accessor(*a, name + ".indices");
    }
  }

  // An accessor the mesh reader will read.
  void read_accessor(std::uint64_t i, const std::string& use) const {
    const json& a = top("accessors")[i];
    const std::string where = item("accessors", i) + " (" + use + ")";
    if (a.contains("sparse")) fail(where + " is sparse: sparse accessors are not read");
    if (!a.contains("bufferView")) fail(where + " has no bufferView: zero-filled or compressed accessors are not read");
  }

  // A JSON value quoted for a message: 'VEC4'.
  static std::string quoted(const json& j) {
    if (!j.is_string()) return describe_json(j);
    const auto& s = j.get_ref<const std::string&>();
    return "'" + (s.size() > 40 ? s.substr(0, 40) + "..." : s) + "'";
  }

  // A top-level array (empty when absent).
  const json& top(const char* name) const {
    static const json empty = json::array();
    const auto it = doc_.find(name);
    if (it == doc_.end()) return empty;
    if (!it->is_array()) fail(std::string(name) + " is " + describe_json(*it) + ", not an array");
    return *it;
  }

  const json& element(const char* array, std::size_t i) const {
    const json& e = top(array)[i];
    if (!e.is_object()) fail(item(array, i) + " is " + describe_json(e) + ", not an object");
    return e;
  }

  std::optional<std::uint64_t> number(const json& object, const char* key, const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) return std::nullopt;
    if (!it->is_number_unsigned()) fail(field(where, key) + " is " + describe_json(*it) + ", not a non-negative integer");
    return it->get<std::uint64_t>();
  }

  std::uint64_t required(const json& object, const char* key, const std::string& where) const {
    const auto v = number(object, key, where);
    if (!v) fail(field(where, key) + " is missing");
    return *v;
  }

  // An index into the top-level `array`, checked against its size.
  std::optional<std::uint64_t> reference(const json& object, const char* key, const std::string& where, const char* array,
                                         bool is_required) const {
    const auto i = is_required ? std::optional(required(object, key, where)) : number(object, key, where);
    if (i && *i >= top(array).size())
      fail(field(where, key) + " is " + str(*i) + " but the file has " + str(top(array).size()) + " " + array);
    return i;
  }

  void node_list(const json& object, const char* key, const std::string& where) const {
    const auto list = object.find(key);
    if (list == object.end()) return;
    const std::string name = field(where, key);
    if (!list->is_array()) fail(name + " is " + describe_json(*list) + ", not an array");
    const std::size_t nodes = top("nodes").size();
    for (std::size_t k = 0; k < list->size(); ++k) {
      const json& entry = (*list)[k];
      if (!entry.is_number_unsigned() || entry.get<std::uint64_t>() >= nodes)
        fail(item(name, k) + " is " + describe_json(entry) + ", not an index below the " + str(nodes) + " nodes");
    }
  }

  void numbers(const json& object, const char* key, std::size_t n, const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) return;
    const std::string name = field(where, key);
    if (!it->is_array() || it->size() != n) fail(name + " is not an array of " + str(n) + " numbers");
    for (std::size_t i = 0; i < n; ++i) {
      const json& v = (*it)[i];
      if (!v.is_number()) fail(item(name, i) + " is " + describe_json(v) + ", not a number");
      if (!std::isfinite(v.get<double>())) fail(item(name, i) + " is not finite");
    }
  }

  // ---- tinygltf ----

  tinygltf::Model run_tinygltf(const std::vector<char>& bytes, std::string_view text) const {
    FileAccess access;
    access.base = path_.parent_path().empty() ? "." : path_.parent_path().string();
    tinygltf::TinyGLTF gltf;
    gltf.SetFsCallbacks({&file_exists, &expand_path, &read_whole_file, nullptr, &access});
    gltf.SetImageLoader(&skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    bool ok = false;
    try {
      ok = glb_ ? gltf.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                            unsigned(bytes.size()), access.base)
                : gltf.LoadASCIIFromString(&model, &err, &warn, text.data(), unsigned(text.size()), access.base);
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {  // a path tinygltf does not guard, e.g. .at() on empty data
      err = e.what();
    }
    if (!ok || !err.empty()) refuse(model, err, access);
    if (!warn.empty()) log::warn(file_, ": ", first_line(warn));
    return model;
  }

  // tinygltf failed after the checks above: name the element it was reading.
  [[noreturn]] void refuse(const tinygltf::Model& partial, const std::string& err, const FileAccess& access) const {
    const std::string text = first_line(err);
    // Buffers load first, one by one: the first one missing from the model is the one that failed.
    const json& buffers = top("buffers");
    if (partial.buffers.size() < buffers.size()) {
      const std::size_t i = partial.buffers.size();
      const std::string where = item("buffers", i);
      const std::string uri = buffers[i].value("uri", "");
      const std::uint64_t length = buffers[i].value("byteLength", std::uint64_t(0));
      if (!access.problem.empty()) fail(where + ".uri " + quoted(uri) + ": " + access.problem);
      if (uri.rfind("data:", 0) == 0)
        fail(where + ".uri: its base64 data does not decode to byteLength (" + str(length) + ") bytes");
      if (!access.path.empty() && access.size != length)
        fail(where + ".byteLength " + str(length) + " differs from the size of " + access.path + " (" + str(access.size) +
             " bytes)");
      fail(where + ": " + text);
    }
    const std::pair<const char*, std::size_t> parsed[] = {
        {"bufferViews", partial.bufferViews.size()}, {"accessors", partial.accessors.size()},
        {"meshes", partial.meshes.size()},           {"nodes", partial.nodes.size()},
        {"scenes", partial.scenes.size()},           {"materials", partial.materials.size()},
        {"images", partial.images.size()},           {"textures", partial.textures.size()},
        {"animations", partial.animations.size()},   {"skins", partial.skins.size()},
        {"samplers", partial.samplers.size()},       {"cameras", partial.cameras.size()}};
    for (const auto& [name, count] : parsed) {
      const auto it = doc_.find(name);
      if (it != doc_.end() && it->is_array() && count < it->size()) fail(item(name, count) + ": " + text);
    }
    fail("not read by tinygltf: " + text);
  }

  fs::path path_;
  std::string file_;
  bool glb_ = false;
  std::optional<std::uint64_t> bin_size_;
  json doc_;
};

}  // namespace

tinygltf::Model load_gltf_model(const std::filesystem::path& path) { return Loader(path).load(); }

}  // namespace nf::io
