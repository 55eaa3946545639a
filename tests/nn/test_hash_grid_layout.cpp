// The hash-grid encoding written into columns of wider rows (engine/nn/hash_grid.hpp,
// HashGridLayout): the same values as the reference, shifted by the offset, the tail zeroed, the
// columns before it untouched; the adjoint reads the same columns.
#include <doctest/doctest.h>

#include "engine/core/error.hpp"
#include "engine/nn/hash_grid.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;

TEST_CASE("hash grid into columns [offset, offset + dim) of wider rows") {
  auto& ctx = test::context();
  const nn::HashGridConfig c{4, 2, 10, 4, 32};
  const nn::HashGrid grid(c);
  const std::uint32_t batch = 37, stride = 16, offset = 3;  // dim 8: columns 3..10, tail 11..15
  const auto points = test::random_f32(batch * 3, 4, 0.f, 1.f);
  const auto table = test::random_f32(c.parameter_count(), 5);
  const auto ref = nn::hash_grid_forward_ref(c, points, table, batch);
  gpu::Buffer<float> d_points(ctx, std::span<const float>(points), "p"), d_table(ctx, std::span<const float>(table), "t");
  gpu::Buffer<float> rows(ctx, std::vector<float>(batch * stride, 7.f), "rows");
  gpu::Stream s(ctx);
  grid.forward(s, d_points, d_table, rows, batch, {stride, offset});
  s.submit_and_wait();
  const auto got = rows.download();
  for (std::uint32_t i = 0; i < batch; ++i) {
    for (std::uint32_t k = 0; k < offset; ++k) CHECK(got[i * stride + k] == 7.f);  // not ours: untouched
    for (std::uint32_t k = 0; k < c.output_dim(); ++k)
      CHECK(got[i * stride + offset + k] == doctest::Approx(ref[i * c.output_stride() + k]).epsilon(1e-5));
    for (std::uint32_t k = offset + c.output_dim(); k < stride; ++k) CHECK(got[i * stride + k] == 0.f);
  }
  // The adjoint reads the same columns: a gradient only in column offset + 1 (level 0, feature 1).
  std::vector<float> grad(batch * stride, 0.f);
  for (std::uint32_t i = 0; i < batch; ++i) grad[i * stride + offset + 1] = 1.f, grad[i * stride] = 100.f;
  gpu::Buffer<float> d_grad(ctx, std::span<const float>(grad), "g"), d_gtable(ctx, c.parameter_count(), "gt");
  d_gtable.fill_u32(0);
  grid.backward(s, d_points, d_table, d_grad, d_gtable, {}, batch, false, {stride, offset});
  s.submit_and_wait();
  const auto gt = d_gtable.download();
  double level0_feature1 = 0, other = 0;
  const std::uint32_t level_size = c.table_size() * c.features;
  for (std::size_t e = 0; e < gt.size(); ++e) (e < level_size && e % 2 == 1 ? level0_feature1 : other) += std::fabs(gt[e]);
  CHECK(level0_feature1 == doctest::Approx(batch).epsilon(1e-4));  // trilinear weights sum to one per sample
  CHECK(other == 0.0);
  CHECK_THROWS_AS(grid.forward(s, d_points, d_table, rows, batch, {stride, 9}), InputError);  // 9 + 8 > 16
}
