#pragma once
// Shared by the fuzz targets: the readers take paths, so each input is written to a per-process
// temporary file with the right extension. nf::Error (bad input, named) is the expected outcome of
// garbage; anything else (a crash, a sanitizer report, another exception) is a finding.
//
// Readers of .npz files that nf_gpu writes itself (grids, roots, per-vertex fur, a SMAL model) get
// structured inputs: the bytes describe arrays, which are written as a valid .npz, so the fuzzer
// explores the reader's checks of names, shapes and values instead of zip checksums (the zip layer
// has its own target, fuzz_npz; members are stored, not deflated, for speed). Per array, in order:
//   1 byte   flags: bit 0 drops the array, bits 1-2 its dtype (<f4, <f8, <i4, <u4 in that order
//            starting at the array's usual dtype), bits 3-4 the rank (0-3)
//   2 bytes  per dimension, little endian, modulo 8193 (element count capped at 2^16: larger
//            arrays add nothing to the checks and slow every execution)
//   1 byte   n, then 4 bytes for each of the first n values (float32 or int32 bits); the others
//            follow a fixed small pattern, so a short input can describe a large array
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "engine/io/npz.hpp"
#include "tests/support/files.hpp"

namespace nf::fuzz {

inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const auto path = std::filesystem::temp_directory_path() / ("nf_fuzz_" + std::to_string(getpid()) + extension);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  test::remove_at_exit(path);
  return path;
}

// A per-process scratch folder, emptied for each input.
inline std::filesystem::path input_folder(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("nf_fuzz_" + std::to_string(getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  test::remove_at_exit(dir);
  return dir;
}

// Reads the input front to back; past its end every read gives zero.
class FuzzBytes {
 public:
  FuzzBytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool exhausted() const { return at_ >= size_; }
  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  std::uint32_t u16() { return std::uint32_t(byte()) | std::uint32_t(byte()) << 8; }
  std::uint32_t u32() { return u16() | u16() << 16; }
  // The rest as text.
  std::string rest() {
    std::string s(reinterpret_cast<const char*>(data_ + std::min(at_, size_)), size_ - std::min(at_, size_));
    at_ = size_;
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_, at_ = 0;
};

struct NpzField {
  std::string name;
  std::string dtype;  // the usual one: <f4, <f8, <i4 or <u4
};

inline void write_fuzz_npz(const std::filesystem::path& file, FuzzBytes& in, const std::vector<NpzField>& fields) {
  static const std::vector<std::string> dtypes = {"<f4", "<f8", "<i4", "<u4"};
  std::vector<io::NpyWrite> arrays;
  for (const NpzField& f : fields) {
    const std::uint8_t flags = in.byte();
    const std::size_t usual = std::size_t(std::find(dtypes.begin(), dtypes.end(), f.dtype) - dtypes.begin()) % dtypes.size();
    io::NpyWrite a{f.name, {}, dtypes[(usual + ((flags >> 1) & 3)) % dtypes.size()], {}};
    std::uint64_t count = 1;
    for (int d = 0; d < ((flags >> 3) & 3); ++d) {
      a.shape.push_back(in.u16() % 8193);
      count *= a.shape.back();
    }
    if (count > (1u << 16)) a.shape.assign(1, 1), count = 1;
    const bool integer = a.dtype == "<i4" || a.dtype == "<u4";
    const std::uint64_t given = in.byte();
    a.values.resize(count);
    for (std::uint64_t i = 0; i < count; ++i) {
      if (i >= given) {
        a.values[i] = integer ? double(i % 5) : double(i % 17) * 0.125 - 1.0;
        continue;
      }
      const std::uint32_t bits = in.u32();
      if (a.dtype == "<i4") a.values[i] = double(std::int32_t(bits));
      else if (a.dtype == "<u4") a.values[i] = double(bits);
      else {
        float v;
        std::memcpy(&v, &bits, 4);
        a.values[i] = double(v);
      }
    }
    if (!(flags & 1)) arrays.push_back(std::move(a));
  }
  if (arrays.empty()) arrays.push_back({"unrelated", {1}, "<f4", {0.0}});  // libzip writes no empty archive
  io::write_npz(file, arrays, io::NpzMembers::stored);
}

}  // namespace nf::fuzz
