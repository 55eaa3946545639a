#pragma once
// Little helpers shared by the binary readers: a byte view that checks every read against the end
// of the file and names the file and the field that ran past it.
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "engine/core/error.hpp"

namespace nf::io {

static_assert(std::endian::native == std::endian::little, "nf_gpu's file formats assume a little-endian host");

inline std::vector<char> read_file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open");
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class ByteReader {
 public:
  ByteReader(const std::vector<char>& bytes, std::string source) : bytes_(bytes), source_(std::move(source)) {}
  std::size_t position() const { return position_; }
  std::size_t remaining() const { return bytes_.size() - position_; }
  void seek(std::size_t p) {
    if (p > bytes_.size()) throw InputError(source_ + ": offset " + std::to_string(p) + " lies beyond the end of the file");
    position_ = p;
  }

  // Copies `count` elements of T into `out`, or throws naming `field` if the file is too short.
  template <class T>
  void read(T* out, std::uint64_t count, const std::string& field) {
    if (count > remaining() / sizeof(T))
      throw InputError(source_ + ": " + field + " needs " + std::to_string(count * sizeof(T)) + " bytes at offset " +
                       std::to_string(position_) + " but the file ends after " + std::to_string(remaining()) +
                       " (truncated, or a count is wrong)");
    if (count == 0) return;  // `out` may be the null data() of an empty vector: memcpy must not see it
    std::memcpy(out, bytes_.data() + position_, count * sizeof(T));
    position_ += count * sizeof(T);
  }
  template <class T>
  T value(const std::string& field) {
    T v;
    read(&v, 1, field);
    return v;
  }

 private:
  const std::vector<char>& bytes_;
  std::string source_;
  std::size_t position_ = 0;
};

template <class T>
void write_array(std::ostream& out, const std::vector<T>& values) {
  out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(T)));
}

}  // namespace nf::io
