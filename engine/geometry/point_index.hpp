#pragma once
// Nearest-neighbour queries over a fixed cloud of 3D points (a KD-tree from Debian's nanoflann).
// Queries are const and may run from several threads at once.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace nf::geometry {

class PointIndex {
 public:
  explicit PointIndex(std::span<const float> xyz);  // the points must outlive the index
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  std::size_t size() const;
  // Index of the nearest point and its squared distance.
  std::pair<std::uint32_t, float> nearest(const float query[3]) const;
  // The k nearest (fewer if the cloud is smaller), closest first.
  std::vector<std::uint32_t> nearest_k(const float query[3], std::size_t k) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nf::geometry
