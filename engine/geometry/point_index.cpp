#include "engine/geometry/point_index.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <exception>
#include <atomic>
#include <mutex>
#include <thread>

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

void parallel_for(std::size_t count, const std::function<void(std::size_t, std::size_t)>& body) {
  const std::size_t threads = std::max<std::size_t>(1, std::min<std::size_t>(std::thread::hardware_concurrency(), count / 1024 + 1));
  std::vector<std::thread> pool;
  std::vector<std::exception_ptr> errors(threads);
  const std::size_t chunk = (count + threads - 1) / threads;
  try {
    for (std::size_t t = 0; t < threads; ++t) {
      const std::size_t begin = t * chunk, end = std::min(count, begin + chunk);
      if (begin < end)
        pool.emplace_back([&, t, begin, end] {
          try {
            body(begin, end);
          } catch (...) {
            errors[t] = std::current_exception();  // rethrown on the calling thread
          }
        });
    }
  } catch (...) {
    for (auto& th : pool) th.join();
    throw;
  }
  for (auto& th : pool) th.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

void for_each_dynamic(int count, const std::function<void(int)>& body) {
  const int threads = std::max(1, std::min<int>(int(std::thread::hardware_concurrency()), count));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto worker = [&] {
    for (int k = next++; k < count; k = next++) {
      try {
        body(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace nf::geometry
