// What the driver's subgroups really are, checked against the assumptions of nf_workgroup.glsl:
// subgroups tile the workgroup, lanes are distinct, arithmetic covers the real lane count.
#include <doctest/doctest.h>

#include <cstdlib>
#include <set>

#include "engine/gpu/kernel.hpp"
#include "engine/gpu/stream.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::gpu;

TEST_CASE("subgroups tile the workgroup and their arithmetic spans the real lane count") {
  auto& ctx = test::context();
  const std::uint32_t wg = 256;
  Buffer<std::uint32_t> probe(ctx, wg * 8, "subgroup probe");
  Stream s(ctx);
  s.dispatch_groups(ctx.kernel("gpu/subgroup_probe", {{0, wg}}), {probe}, Elements(1));
  s.submit_and_wait();
  const auto p = probe.download();
  const std::uint32_t subgroups = p[1];
  REQUIRE(subgroups > 0);
  REQUIRE(wg % subgroups == 0);
  const std::uint32_t lanes = wg / subgroups;
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  for (std::uint32_t i = 0; i < wg; ++i) {
    const std::uint32_t id = p[i * 8], lane = p[i * 8 + 3];
    CHECK(p[i * 8 + 1] == subgroups);
    CHECK(id < subgroups);
    CHECK(lane < lanes);
    CHECK(p[i * 8 + 4] == lane + 1);  // inclusive add of 1
    CHECK(p[i * 8 + 5] == lanes);     // add of 1 over the subgroup
    seen.insert({id, lane});
  }
  CHECK(seen.size() == wg);
  if (p[2] != lanes)
    MESSAGE("driver reports gl_SubgroupSize " << p[2] << " but runs " << lanes
                                              << "-lane subgroups; nf_workgroup.glsl uses the real count");
  if (const char* expected = std::getenv("NF_EXPECT_SUBGROUP_LANES");
      expected && ctx.info().driver == "Mesa lavapipe")
    CHECK(lanes == std::uint32_t(std::atoi(expected)));
}
