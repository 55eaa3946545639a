#pragma once
// A set of strands (polylines, root first) as the engine and the file formats share it: points
// stored contiguously, strand s owning points [offsets[s], offsets[s+1]). Optional per-point
// thickness, transparency and colour, and a per-strand region id, travel with the geometry.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace nf::io {

struct StrandSet {
  std::vector<float> points;           // xyz per point
  std::vector<std::uint32_t> offsets;  // strands + 1 entries, offsets[0] == 0
  std::vector<float> thickness;        // per point (empty: absent)
  std::vector<float> transparency;     // per point (empty: absent)
  std::vector<float> colors;           // rgb per point (empty: absent)
  std::vector<std::uint16_t> regions;  // per strand (empty: absent)

  std::uint32_t strand_count() const { return offsets.empty() ? 0u : std::uint32_t(offsets.size() - 1); }
  std::uint64_t point_count() const { return points.size() / 3; }
  std::uint32_t points_in(std::uint32_t strand) const { return offsets[strand + 1] - offsets[strand]; }

  // N strands of L points each from contiguous xyz (the engine's fixed-length layout).
  static StrandSet uniform(std::uint32_t strands, std::uint32_t points_per_strand, std::vector<float> xyz);
  // Throws InputError naming `source` and the inconsistent field (sizes, offsets, NaN/Inf).
  void validate(const std::string& source) const;
};

}  // namespace nf::io
