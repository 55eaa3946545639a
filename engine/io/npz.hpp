#pragma once
// Arrays from NumPy .npz files (zip archives of .npy, stored or deflated; read with libzip), and
// writing them (fixtures in the same layout as a converted SMAL model).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nf::io {

struct NpyArray {
  std::vector<std::uint64_t> shape;
  std::vector<double> values;  // converted from float32/float64/int, C order
};

// Throws InputError naming the file and the array when it is missing or not a numeric array.
NpyArray read_npz_array(const std::filesystem::path& file, const std::string& name);
std::vector<std::string> npz_array_names(const std::filesystem::path& file);

// Writes arrays (C order; libzip deflates each member unless stored) to a new .npz, atomically. dtype: <f8, <f4, <i8, <i4 or <u4.
struct NpyWrite {
  std::string name;
  std::vector<std::uint64_t> shape;
  std::string dtype = "<f8";
  std::vector<double> values;
};
// stored: members uncompressed, as numpy.savez writes them (the fuzz targets use it: a deflate
// stream's set-up costs more than the reader's checks they exercise).
enum class NpzMembers { deflated, stored };
void write_npz(const std::filesystem::path& file, const std::vector<NpyWrite>& arrays, NpzMembers members = NpzMembers::deflated);

}  // namespace nf::io
