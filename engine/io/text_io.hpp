#pragma once
// Shortest round-trip text for floats (std::to_chars), shared by the text writers (OBJ, USDA).
#include <charconv>
#include <cstdint>
#include <ostream>

namespace nf::io {

inline void put_float(std::ostream& out, float v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  out.write(buffer, r.ptr - buffer);
}

inline void put_integer(std::ostream& out, std::int64_t v) {
  char buffer[24];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  out.write(buffer, r.ptr - buffer);
}

// xyz[0..2] separated by `separator` (" " for OBJ, ", " for USD tuples).
inline void put_xyz(std::ostream& out, const float* xyz, const char* separator = " ") {
  put_float(out, xyz[0]);
  out << separator;
  put_float(out, xyz[1]);
  out << separator;
  put_float(out, xyz[2]);
}

}  // namespace nf::io
