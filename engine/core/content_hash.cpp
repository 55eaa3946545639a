#include "engine/core/content_hash.hpp"

#include <cstdio>
#include <fstream>
#include <vector>

#include "engine/core/error.hpp"

namespace nf {
namespace {

constexpr std::uint64_t kOffset = 0xcbf29ce484222325ull, kPrime = 0x100000001b3ull;

std::uint64_t fnv1a(std::uint64_t h, const char* data, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h = (h ^ std::uint8_t(data[i])) * kPrime;
  return h;
}

std::string hex(std::uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace

std::string hash_bytes(std::string_view bytes) { return hex(fnv1a(kOffset, bytes.data(), bytes.size())); }

std::string hash_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot be read (for the pipeline's input hash)");
  std::vector<char> buf(1 << 20);
  std::uint64_t h = kOffset;
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    h = fnv1a(h, buf.data(), std::size_t(in.gcount()));
  }
  if (in.bad()) throw InputError(path.string() + ": read error (for the pipeline's input hash)");
  return hex(h);
}

}  // namespace nf
