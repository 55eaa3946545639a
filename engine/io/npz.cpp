#include "engine/io/npz.hpp"

#include <zip.h>

#include <cstring>
#include <limits>
#include <memory>
#include <sstream>

#include "engine/core/error.hpp"

namespace nf::io {
namespace {

struct Archive {
  zip_t* z = nullptr;
  explicit Archive(const std::filesystem::path& file) {
    int error = 0;
    z = zip_open(file.c_str(), ZIP_RDONLY, &error);
    if (!z) throw InputError(file.string() + ": cannot open as an .npz (zip) archive (libzip error " + std::to_string(error) + ")");
  }
  ~Archive() {
    if (z) zip_discard(z);
  }
};

NpyArray parse_npy_checked(const std::vector<char>& b, const std::string& where);

NpyArray parse_npy(const std::vector<char>& b, const std::string& where) {
  try {
    return parse_npy_checked(b, where);
  } catch (const std::logic_error&) {  // stoull / stoi on a malformed header
    throw InputError(where + ": malformed .npy header");
  }
}

NpyArray parse_npy_checked(const std::vector<char>& b, const std::string& where) {
  if (b.size() < 10 || std::memcmp(b.data(), "\x93NUMPY", 6) != 0) throw InputError(where + ": not a .npy array");
  const int major = static_cast<unsigned char>(b[6]);
  const std::size_t header_length = major == 1 ? std::size_t(static_cast<unsigned char>(b[8]) | static_cast<unsigned char>(b[9]) << 8)
                                               : std::size_t(static_cast<unsigned char>(b[8])) | std::size_t(static_cast<unsigned char>(b[9])) << 8 |
                                                     std::size_t(static_cast<unsigned char>(b[10])) << 16 | std::size_t(static_cast<unsigned char>(b[11])) << 24;
  const std::size_t start = major == 1 ? 10 : 12;
  if (start + header_length > b.size()) throw InputError(where + ": truncated .npy header");
  const std::string header(b.begin() + std::ptrdiff_t(start), b.begin() + std::ptrdiff_t(start + header_length));
  const auto field = [&](const std::string& key) {
    const std::size_t at = header.find("'" + key + "'");
    if (at == std::string::npos) throw InputError(where + ": .npy header has no '" + key + "'");
    return header.substr(header.find(':', at) + 1);
  };
  std::string descr = field("descr");
  descr = descr.substr(descr.find('\'') + 1);
  descr = descr.substr(0, descr.find('\''));
  if (field("fortran_order").find("True") < field("fortran_order").find(','))
    throw InputError(where + ": Fortran-ordered arrays are not read");
  NpyArray a;
  std::string shape = field("shape");
  shape = shape.substr(shape.find('(') + 1, shape.find(')') - shape.find('(') - 1);
  std::stringstream ss(shape);
  std::string dim;
  std::uint64_t count = 1;
  while (std::getline(ss, dim, ','))
    if (dim.find_first_not_of(" ") != std::string::npos) {
      a.shape.push_back(std::stoull(dim));
      if (a.shape.back() != 0 && count > std::numeric_limits<std::uint64_t>::max() / a.shape.back())
        throw InputError(where + ": shape too large");
      count *= a.shape.back();
    }
  const std::size_t data = start + header_length;
  const std::size_t size = descr.size() >= 3 ? std::size_t(std::stoi(descr.substr(2))) : 0;
  if (descr[0] == '>' || size == 0) throw InputError(where + ": unsupported dtype '" + descr + "' (little-endian numbers only)");
  if (count > (b.size() - data) / size) throw InputError(where + ": data shorter than its shape (truncated?)");
  a.values.resize(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    const char* p = b.data() + data + i * size;
    const char kind = descr[1];
    if (kind == 'f' && size == 8) { double v; std::memcpy(&v, p, 8); a.values[i] = v; }
    else if (kind == 'f' && size == 4) { float v; std::memcpy(&v, p, 4); a.values[i] = v; }
    else if (kind == 'i' && size == 8) { std::int64_t v; std::memcpy(&v, p, 8); a.values[i] = double(v); }
    else if (kind == 'i' && size == 4) { std::int32_t v; std::memcpy(&v, p, 4); a.values[i] = v; }
    else if (kind == 'u' && size == 8) { std::uint64_t v; std::memcpy(&v, p, 8); a.values[i] = double(v); }
    else if (kind == 'u' && size == 4) { std::uint32_t v; std::memcpy(&v, p, 4); a.values[i] = v; }
    else throw InputError(where + ": unsupported dtype '" + descr + "'");
  }
  return a;
}

}  // namespace

NpyArray read_npz_array(const std::filesystem::path& file, const std::string& name) {
  Archive archive(file);
  const std::string entry = name + ".npy", where = file.string() + ": array '" + name + "'";
  zip_stat_t st;
  if (zip_stat(archive.z, entry.c_str(), 0, &st) != 0) throw InputError(where + " is missing");
  if (st.size > (1ull << 30)) throw InputError(where + " is larger than 1 GiB");
  std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> f(zip_fopen(archive.z, entry.c_str(), 0), zip_fclose);
  if (!f) throw InputError(where + " cannot be read");
  std::vector<char> bytes(st.size);
  if (zip_fread(f.get(), bytes.data(), st.size) != zip_int64_t(st.size)) throw InputError(where + " is truncated");
  return parse_npy(bytes, where);
}

std::vector<std::string> npz_array_names(const std::filesystem::path& file) {
  Archive archive(file);
  std::vector<std::string> names;
  const zip_int64_t n = zip_get_num_entries(archive.z, 0);
  for (zip_int64_t i = 0; i < n; ++i) {
    std::string name = zip_get_name(archive.z, zip_uint64_t(i), 0);
    if (name.size() > 4 && name.substr(name.size() - 4) == ".npy") names.push_back(name.substr(0, name.size() - 4));
  }
  return names;
}

namespace {

// One .npy file: the version-1 header padded so the data starts on a 64-byte boundary.
std::string npy_bytes(const NpyWrite& a, const std::string& where) {
  std::uint64_t count = 1;
  std::string shape;
  for (std::uint64_t d : a.shape) count *= d, shape += (shape.empty() ? "" : ", ") + std::to_string(d);
  shape = "(" + shape + (a.shape.size() == 1 ? ",)" : ")");  // Python's tuple spelling: "(3,)", "(3, 4)"
  if (count != a.values.size()) throw InternalError(where + ": shape and value count disagree");
  std::string header = "{'descr': '" + a.dtype + "', 'fortran_order': False, 'shape': " + shape + ", }";
  const std::size_t total = 10 + header.size() + 1;
  header += std::string((64 - total % 64) % 64, ' ') + "\n";
  std::string out("\x93NUMPY\x01\x00", 8);
  out += char(header.size() & 0xff), out += char(header.size() >> 8);
  out += header;
  for (double v : a.values) {
    char b[8];
    std::size_t n = 0;
    if (a.dtype == "<f8") std::memcpy(b, &v, n = 8);
    else if (a.dtype == "<f4") { const float f = float(v); std::memcpy(b, &f, n = 4); }
    else if (a.dtype == "<i8") { const std::int64_t i = std::int64_t(v); std::memcpy(b, &i, n = 8); }
    else if (a.dtype == "<u4") { const std::uint32_t u = std::uint32_t(v); std::memcpy(b, &u, n = 4); }
    else if (a.dtype == "<i4") { const std::int32_t i = std::int32_t(v); std::memcpy(b, &i, n = 4); }
    else throw InternalError(where + ": unsupported dtype " + a.dtype);
    out.append(b, n);
  }
  return out;
}

}  // namespace

void write_npz(const std::filesystem::path& file, const std::vector<NpyWrite>& arrays, NpzMembers members) {
  const std::filesystem::path temp = file.string() + ".partial";
  std::filesystem::remove(temp);
  int error = 0;
  zip_t* z = zip_open(temp.c_str(), ZIP_CREATE | ZIP_EXCL, &error);
  if (!z) throw InputError(file.string() + ": cannot create (libzip error " + std::to_string(error) + ")");
  std::vector<std::string> buffers;  // libzip reads them at zip_close
  buffers.reserve(arrays.size());
  for (const NpyWrite& a : arrays) {
    try {
      buffers.push_back(npy_bytes(a, file.string() + ": array '" + a.name + "'"));
    } catch (...) {
      zip_discard(z);
      throw;
    }
    zip_source_t* src = zip_source_buffer(z, buffers.back().data(), buffers.back().size(), 0);
    const zip_int64_t index = src ? zip_file_add(z, (a.name + ".npy").c_str(), src, ZIP_FL_OVERWRITE) : -1;
    if (index < 0 || (members == NpzMembers::stored && zip_set_file_compression(z, zip_uint64_t(index), ZIP_CM_STORE, 0) != 0)) {
      if (src && index < 0) zip_source_free(src);
      zip_discard(z);
      throw InputError(file.string() + ": cannot add array '" + a.name + "'");
    }
  }
  if (zip_close(z) != 0) {
    zip_discard(z);
    std::filesystem::remove(temp);
    throw InputError(file.string() + ": cannot write the archive");
  }
  std::filesystem::rename(temp, file);
}

}  // namespace nf::io
