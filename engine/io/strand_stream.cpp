#include "engine/io/strand_stream.hpp"

#include <cmath>
#include <string>

#include "engine/core/error.hpp"

namespace nf::io {

StrandStream StrandStream::of(const StrandSet& set) {
  StrandStream s;
  s.strands = set.strand_count();
  s.points = set.point_count();
  s.points_in = [&set](std::uint64_t i) { return set.points_in(std::uint32_t(i)); };
  s.each_chunk = [&set](const PointSink& sink) {
    if (!set.points.empty()) sink(std::span<const float>(set.points));
  };
  if (!set.thickness.empty())
    s.width = [&set](std::uint64_t i, std::uint32_t k) { return set.thickness[set.offsets[i] + k]; };
  if (!set.regions.empty()) s.region = [&set](std::uint64_t i) { return std::int32_t(set.regions[i]); };
  if (!set.colors.empty())
    s.color = [&set](std::uint64_t i, std::uint32_t k) {
      const float* c = &set.colors[3 * (std::size_t(set.offsets[i]) + k)];
      return glm::vec3(c[0], c[1], c[2]);
    };
  return s;
}

void require_finite_points(const std::filesystem::path& path, std::span<const float> xyz, std::uint64_t floats_before) {
  for (std::size_t i = 0; i < xyz.size(); ++i)
    if (!std::isfinite(xyz[i]))
      throw InputError(path.string() + ": strand point " + std::to_string((floats_before + i) / 3) + " is not finite (" + std::to_string(xyz[i]) + ")");
}

}  // namespace nf::io
