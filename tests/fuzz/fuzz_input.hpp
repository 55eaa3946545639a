#pragma once
// Shared by the fuzz targets: the readers take paths, so each input is written to a per-process
// temporary file with the right extension. nf::Error (bad input, named) is the expected outcome of
// garbage; anything else (a crash, a sanitizer report, another exception) is a finding.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace nf::fuzz {

inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const auto path = std::filesystem::temp_directory_path() / ("nf_fuzz_" + std::to_string(getpid()) + extension);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

}  // namespace nf::fuzz
