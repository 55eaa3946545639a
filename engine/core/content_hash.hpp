#pragma once
// Content hashes for the pipeline's cache keys: 64-bit FNV-1a over bytes, as 16 hex digits.
// Not cryptographic: it tells "this input changed" from "same input", nothing more.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace nf {

std::string hash_bytes(std::string_view bytes);
// Throws InputError naming the file when it cannot be read.
std::string hash_file(const std::filesystem::path& path);

}  // namespace nf
