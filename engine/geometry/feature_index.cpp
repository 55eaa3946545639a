#include "engine/geometry/feature_index.hpp"

#include <nanoflann.hpp>

#include "engine/core/error.hpp"

namespace nf::geometry {
namespace {

struct Features {
  std::span<const float> data;
  std::size_t dimension;
  std::size_t kdtree_get_point_count() const { return data.size() / dimension; }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return data[i * dimension + d]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Features>, Features, -1, std::uint32_t>;

// Hands every point within the radius to a callback; the search stops when it returns false.
struct VisitResultSet {
  float radius2;
  const std::function<bool(std::uint32_t, float)>& visit;
  bool full() const { return true; }
  float worstDist() const { return radius2; }
  bool addPoint(float distance2, std::uint32_t index) { return distance2 <= radius2 ? visit(index, distance2) : true; }
};

}  // namespace

struct FeatureIndex::Impl {
  Features features;
  Tree tree;
  Impl(std::span<const float> data, std::size_t dimension)
      : features{data, dimension}, tree(int(dimension), features, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
};

FeatureIndex::FeatureIndex(std::span<const float> features, std::size_t dimension) {
  if (dimension == 0 || features.size() % dimension) throw InternalError("FeatureIndex: data is not a multiple of the dimension");
  impl_ = std::make_unique<Impl>(features, dimension);
}
FeatureIndex::~FeatureIndex() = default;

std::size_t FeatureIndex::size() const { return impl_->features.kdtree_get_point_count(); }

void FeatureIndex::visit_within(const float* query, float radius, const std::function<bool(std::uint32_t, float)>& visit) const {
  if (size() == 0 || !(radius > 0)) return;
  VisitResultSet result{radius * radius, visit};
  impl_->tree.findNeighbors(result, query, nanoflann::SearchParams());
}

}  // namespace nf::geometry
