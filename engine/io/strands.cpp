#include "engine/io/strands.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"

namespace nf::io {

StrandSet StrandSet::uniform(std::uint32_t strands, std::uint32_t points_per_strand, std::vector<float> xyz) {
  if (xyz.size() != std::uint64_t(strands) * points_per_strand * 3)
    throw InputError("strands: " + std::to_string(xyz.size()) + " floats for " + std::to_string(strands) + " x " +
                     std::to_string(points_per_strand) + " points");
  StrandSet s;
  s.points = std::move(xyz);
  s.offsets.resize(std::size_t(strands) + 1);
  for (std::uint32_t i = 0; i <= strands; ++i) s.offsets[i] = i * points_per_strand;
  return s;
}

void StrandSet::validate(const std::string& source) const {
  if (points.size() % 3) throw InputError(source + ": point array length " + std::to_string(points.size()) + " is not a multiple of 3");
  const std::uint64_t n = point_count();
  if (!offsets.empty()) {
    if (offsets.front() != 0) throw InputError(source + ": the first strand does not start at point 0");
    for (std::size_t i = 1; i < offsets.size(); ++i)
      if (offsets[i] < offsets[i - 1])
        throw InputError(source + ": strand " + std::to_string(i - 1) + " has a negative point count");
    if (offsets.back() != n)
      throw InputError(source + ": strands cover " + std::to_string(offsets.back()) + " points but " +
                       std::to_string(n) + " are stored");
  } else if (n) {
    throw InputError(source + ": points without strands");
  }
  if (!thickness.empty() && thickness.size() != n) throw InputError(source + ": thickness array does not match the points");
  if (!transparency.empty() && transparency.size() != n) throw InputError(source + ": transparency array does not match the points");
  if (!colors.empty() && colors.size() != 3 * n) throw InputError(source + ": color array does not match the points");
  if (!regions.empty() && regions.size() != strand_count()) throw InputError(source + ": region array does not match the strands");
  require_finite(points, source + ": points");
  require_finite(thickness, source + ": thickness");
  require_finite(transparency, source + ": transparency");
  require_finite(colors, source + ": colors");
}

}  // namespace nf::io
