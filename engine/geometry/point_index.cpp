#include "engine/geometry/point_index.hpp"

#include <nanoflann.hpp>

#include <algorithm>

#include "engine/core/error.hpp"

namespace nf::geometry {
namespace {

struct Cloud {
  std::span<const float> xyz;
  std::size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return xyz[3 * i + dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3, std::uint32_t>;

}  // namespace

struct PointIndex::Impl {
  Cloud cloud;
  Tree tree;
  // nanoflann 1.4 builds the tree in its constructor.
  explicit Impl(std::span<const float> xyz) : cloud{xyz}, tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
};

PointIndex::PointIndex(std::span<const float> xyz) {
  if (xyz.size() % 3) throw InternalError("PointIndex: coordinates are not a multiple of 3");
  impl_ = std::make_unique<Impl>(xyz);
}
PointIndex::~PointIndex() = default;

std::size_t PointIndex::size() const { return impl_->cloud.kdtree_get_point_count(); }

std::pair<std::uint32_t, float> PointIndex::nearest(const float query[3]) const {
  if (size() == 0) throw InternalError("PointIndex: query on an empty cloud");
  std::uint32_t index = 0;
  float distance2 = 0;
  nanoflann::KNNResultSet<float, std::uint32_t> result(1);
  result.init(&index, &distance2);
  impl_->tree.findNeighbors(result, query, nanoflann::SearchParams());
  return {index, distance2};
}

std::vector<std::uint32_t> PointIndex::nearest_k(const float query[3], std::size_t k) const {
  k = std::min(k, size());
  std::vector<std::uint32_t> indices(k);
  std::vector<float> distances(k);
  if (k) k = impl_->tree.knnSearch(query, k, indices.data(), distances.data());
  indices.resize(k);
  return indices;
}

}  // namespace nf::geometry
