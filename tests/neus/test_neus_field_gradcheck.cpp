// The whole NeuS renderer on a tiny case, checked against finite differences: field (encoding,
// SDF network, tetrahedral normals, colour network) -> volume rendering -> colour L1 + mask BCE
// + Eikonal. dL/dparameter from the hand-written adjoints must match central differences of the
// GPU forward for parameters of the SDF network, the colour network and the hash table.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/neus/neus_field.hpp"
#include "engine/neus/render_loss.hpp"
#include "engine/neus/volume_render.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;

namespace {

struct Renderer {
  neus::NeusField field;
  neus::NeusField::Batch batch;
  gpu::Buffer<float> dist, colour, opacity, gcolour, gopacity, gsdf, gcos, grgb, ginv;
  gpu::Buffer<glm::vec4> target, partials;
  std::uint32_t inside = 0;
  float h = 0.02f, inv_s = 30.f, eikonal = 0.1f;
  neus::RenderLossWeights weights;

  Renderer(const neus::NeusFieldConfig& config, std::uint32_t rays, std::uint32_t samples)
      : field(test::context(), config, 7),
        batch(field, rays, samples),
        dist(test::context(), rays * samples, "d"),
        colour(test::context(), rays * 3, "c"),
        opacity(test::context(), rays, "o"),
        gcolour(test::context(), rays * 3, "gc"),
        gopacity(test::context(), rays, "go"),
        gsdf(test::context(), rays * samples, "gs"),
        gcos(test::context(), rays * samples, "gcos"),
        grgb(test::context(), rays * samples * 3, "grgb"),
        ginv(test::context(), 1, "gi"),
        target(test::context(), rays, "t"),
        partials(test::context(), neus::render_loss_partial_count(rays), "p") {
    // Rays from z = -1.2 towards the origin region, targets half inside half outside.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.6f, 0.6f);
    std::vector<glm::vec4> s(batch.n), d(rays), t(rays);
    std::vector<float> di(batch.n);
    for (std::uint32_t r = 0; r < rays; ++r) {
      const glm::vec3 o(u(rng), u(rng), -1.2f);
      const glm::vec3 dir = glm::normalize(glm::vec3(0.2f * u(rng), 0.2f * u(rng), 1.f));
      d[r] = glm::vec4(dir, 0.f);
      for (std::uint32_t j = 0; j < samples; ++j) {
        const float tj = 0.4f + 1.6f * (j + 0.5f) / samples;
        s[r * samples + j] = glm::vec4(o + tj * dir, 0.f);
        di[r * samples + j] = 1.6f / samples;
      }
      const float m = r % 2 ? 1.f : 0.f;
      t[r] = glm::vec4(0.2f + 0.6f * (r % 3) / 2.f, 0.5f, 0.8f - 0.3f * m, m);
      inside += m > 0.5f;
    }
    batch.samples.upload(s);
    batch.dirs.upload(d);
    dist.upload(di);
    target.upload(t);
  }

  // Records the forward (and, when asked, the adjoint); returns the loss.
  double run(bool backward) {
    gpu::Stream s(test::context());
    const neus::VolumeRenderShape shape{batch.rays, batch.samples_per_ray};
    const neus::VolumeRenderParams params{inv_s, 0.5f, 0};
    const neus::VolumeRenderInputBuffers in{batch.sdf.whole(), batch.cos.whole(), dist.whole(), batch.rgb.whole()};
    field.forward(s, batch, h);
    neus::volume_render_forward(s, shape, params, in, {colour.whole(), opacity.whole()});
    neus::render_loss(s, batch.rays, inside, weights, colour.whole(), opacity.whole(), target.whole(), gcolour.whole(),
                      gopacity.whole(), partials.whole());
    if (backward) {
      neus::volume_render_backward(s, shape, params, in, gcolour.whole(), gopacity.whole(),
                                   {gsdf.whole(), gcos.whole(), grgb.whole(), ginv.whole()});
      field.backward(s, batch, h, eikonal, gsdf.whole(), gcos.whole(), grgb.whole());
    }
    s.submit_and_wait();
    const neus::RenderLossTotals totals = neus::sum_render_loss(partials.download(), batch.rays);
    double e = 0;
    for (const float p : batch.eikonal_partials.download()) e += p;
    return totals.loss(weights) + eikonal * e / batch.n;
  }
};

// Central differences of the GPU forward for the `count` parameters of `params` with the largest
// analytic gradients, against the analytic gradient.
void check_parameters(Renderer& r, gpu::Buffer<float>& params, const std::vector<float>& analytic, const std::string& what) {
  std::vector<std::size_t> order(analytic.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::partial_sort(order.begin(), order.begin() + 6, order.end(),
                    [&](std::size_t a, std::size_t b) { return std::fabs(analytic[a]) > std::fabs(analytic[b]); });
  std::vector<float> p = params.download();
  double worst = 0;
  for (int k = 0; k < 6; ++k) {
    const std::size_t i = order[k];
    const float eps = std::max(1e-3f, 1e-2f * std::fabs(p[i]));
    const float keep = p[i];
    p[i] = keep + eps;
    params.upload(p);
    const double plus = r.run(false);
    p[i] = keep - eps;
    params.upload(p);
    const double minus = r.run(false);
    p[i] = keep;
    params.upload(p);
    const double fd = (plus - minus) / (2.0 * eps);
    const double rel = std::fabs(fd - analytic[i]) / std::max(1e-4, std::fabs(double(analytic[i])));
    MESSAGE(what, " parameter ", i, ": analytic ", analytic[i], ", finite differences ", fd);
    CHECK(std::isfinite(analytic[i]));
    worst = std::max(worst, rel);
  }
  CHECK_MESSAGE(worst < 0.1, what, ": worst relative error ", worst);
}

}  // namespace

TEST_CASE("NeuS renderer: parameter gradients against finite differences (frequency and hash-grid fields)") {
  for (const neus::FieldEncoding enc : {neus::FieldEncoding::Frequency, neus::FieldEncoding::HashGrid}) {
    CAPTURE(int(enc));
    neus::NeusFieldConfig config;
    config.encoding = enc;
    config.frequency = {3, 2, true};
    config.hash = {4, 2, 12, 4, 32};
    config.sdf_hidden = {16};
    config.features = 7;
    config.colour_hidden = {16};
    Renderer r(config, 16, 24);
    // Away from the geometric initialisation, whose zero weights on the encoding would leave the
    // hash table without gradient.
    std::vector<float> p = r.field.sdf().parameters().download();
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0.f, 0.1f);
    for (float& x : p)
      if (x != 0.f || rng() % 2) x += noise(rng);
    r.field.sdf().parameters().upload(p);
    const double loss = r.run(true);
    CHECK(std::isfinite(loss));
    const std::vector<float> g_sdf = r.field.sdf().gradients().download();
    const std::vector<float> g_colour = r.field.colour().gradients().download();
    check_parameters(r, r.field.sdf().parameters(), g_sdf, "sdf");
    check_parameters(r, r.field.colour().parameters(), g_colour, "colour");
    if (r.field.has_table()) {
      const std::vector<float> g_table = r.field.table_gradient().download();
      CHECK(*std::max_element(g_table.begin(), g_table.end()) > 0.f);
      check_parameters(r, r.field.table(), g_table, "hash table");
    }
  }
}
