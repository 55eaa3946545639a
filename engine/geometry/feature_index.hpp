#pragma once
// Ball queries over points with more than three coordinates (e.g. position plus a weighted
// direction), a KD-tree from Debian's nanoflann with the dimension chosen at run time. Queries are
// const and may run from several threads at once.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

namespace nf::geometry {

class FeatureIndex {
 public:
  FeatureIndex(std::span<const float> features, std::size_t dimension);  // features must outlive the index
  ~FeatureIndex();
  FeatureIndex(const FeatureIndex&) = delete;
  FeatureIndex& operator=(const FeatureIndex&) = delete;
  std::size_t size() const;
  // Calls visit(index, squared distance) for points within `radius` of the query (dimension
  // floats), in no particular order, until it returns false.
  void visit_within(const float* query, float radius, const std::function<bool(std::uint32_t, float)>& visit) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nf::geometry
