#pragma once
// Arrays from NumPy .npz files (zip archives of .npy, stored or deflated; read with libzip).
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

}  // namespace nf::io
