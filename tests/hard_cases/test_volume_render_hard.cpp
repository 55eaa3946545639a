// Hard cases for NeuS volume rendering: rays that miss or start inside, extreme inv_s, zero-length
// sections, cos on the relu kinks, a 1x1 problem, bad input rejected by name, and a 200k-ray batch
// where the GPU matches the double CPU reference.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/neus/volume_render.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::neus;

namespace {

bool finite(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

struct Rays {
  std::uint32_t samples;
  std::vector<float> sdf, cos, dist, rgb;
  float inv_s = 64.f;
  Rays(std::uint64_t rays, std::uint32_t s, unsigned seed) : samples(s) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (std::uint64_t r = 0; r < rays; ++r) {
      const float tc = 0.3f + 1.4f * u(rng);
      float t = 0;
      for (std::uint32_t i = 0; i < s; ++i) {
        const float d = 2.f / float(s) * (0.5f + u(rng));
        const float c = -1.f + 2.f * u(rng);
        sdf.push_back((tc - t - 0.5f * d) * (0.3f + 0.7f * u(rng)));
        cos.push_back(c);
        dist.push_back(d);
        t += d;
        for (int ch = 0; ch < 3; ++ch) rgb.push_back(u(rng));
      }
    }
  }
  std::uint64_t rays() const { return sdf.size() / samples; }
  VolumeRenderInputs<float> inputs() const { return {sdf, cos, dist, rgb, inv_s}; }
};

VolumeRenderResult run(const Rays& r, float anneal = 0.5f, std::uint64_t chunk_rays = 0) {
  const std::vector<float> gc(r.rays() * 3, 0.7f), go(r.rays(), -0.3f);
  VolumeRenderParams p;
  p.cos_anneal = anneal;
  p.chunk_rays = chunk_rays;
  return volume_render_with_gradients(test::context(), r.samples, r.inputs(), p, gc, go);
}

void require_finite_result(const VolumeRenderResult& res) {
  CHECK(finite(res.outputs.colour));
  CHECK(finite(res.outputs.opacity));
  CHECK(finite(res.grads.sdf));
  CHECK(finite(res.grads.cos));
  CHECK(finite(res.grads.rgb));
  CHECK(std::isfinite(res.grads.inv_s));
  for (float o : res.outputs.opacity) {
    CHECK(o >= 0.f);
    CHECK(o <= 1.0001f);
  }
}

// The value every output and gradient of run(r, anneal) should have: the double reference on the same
// input. Outputs (in [0, 1]) within `out_tol`; each gradient array within `rtol` of its largest
// reference magnitude plus `atol`, as float cancels in dalpha/dsdf where the sigmoid is flat
// (p ~ c) and the gradients there are ~0.
void check_reference(const Rays& r, const VolumeRenderResult& res, float anneal, double out_tol, double rtol,
                     double atol) {
  const auto widen = [](const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); };
  const std::vector<double> sd = widen(r.sdf), cd = widen(r.cos), dd = widen(r.dist), rd = widen(r.rgb);
  const std::vector<double> gc(r.rays() * 3, double(0.7f)), go(r.rays(), double(-0.3f));  // as run() passes them
  const VolumeRenderInputs<double> in{sd, cd, dd, rd, double(r.inv_s)};
  const auto out = volume_render_forward_ref<double>(r.rays(), r.samples, in, anneal);
  const auto g = volume_render_backward_ref<double>(r.rays(), r.samples, in, anneal, gc, go);
  // max |got - want| <= rel_tol * max |want| + abs_tol.
  const auto agrees = [](const char* what, const std::vector<float>& got, const std::vector<double>& want,
                         double rel_tol, double abs_tol) {
    REQUIRE(got.size() == want.size());
    double err = 0, largest = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      err = std::max(err, std::fabs(got[i] - want[i]));
      largest = std::max(largest, std::fabs(want[i]));
    }
    INFO(what << ": largest error " << err << ", largest reference value " << largest);
    CHECK(err <= rel_tol * largest + abs_tol);
  };
  agrees("opacity", res.outputs.opacity, out.opacity, 0, out_tol);
  agrees("colour", res.outputs.colour, out.colour, 0, out_tol);
  agrees("dL/dsdf", res.grads.sdf, g.sdf, rtol, atol);
  agrees("dL/dcos", res.grads.cos, g.cos, rtol, atol);
  agrees("dL/drgb", res.grads.rgb, g.rgb, rtol, atol);
  CHECK(std::fabs(res.grads.inv_s - g.inv_s) <= 10 * rtol * std::fabs(g.inv_s) + atol);  // a sum: more rounding
}

}  // namespace

TEST_CASE("ray missing the object: opacity ~ 0, finite gradients") {
  Rays r(4, 64, 1);
  for (float& s : r.sdf) s = 0.5f + std::fabs(s);
  const auto res = run(r);
  require_finite_result(res);
  for (float o : res.outputs.opacity) CHECK(o < 1e-3f);
  // sdf +- |h| >= 0.47 and inv_s = 64: p = c = 1 in float (1 - e^-30 in double), so every sample
  // has only the guard's alpha a = 1e-5 / (1 + 1e-5), T_i = q^i with q = 1 - a + 1e-7; the colour
  // is sum_i a q^i rgb_i and dL/drgb_i = a q^i gcol. dalpha/dsdf, dalpha/dcos and dalpha/dinv_s are
  // ~ inv_s e^-30 ~ 1e-12: those gradients are 0.
  // float rounds the guard (p + 1e-5 is 1.0000100136 in float): the GPU's a is 0.14 % above the
  // double one, so the shares allow 0.3 %.
  const double a = 1e-5 / (1 + 1e-5), q = 1 - a + 1e-7;
  for (std::uint64_t ray = 0; ray < r.rays(); ++ray) {
    CHECK(res.outputs.opacity[ray] / (a * (1 - std::pow(q, 64)) / (1 - q)) == doctest::Approx(1.0).epsilon(3e-3));
    for (int ch = 0; ch < 3; ++ch) {
      double colour = 0;
      for (int i = 0; i < 64; ++i) colour += a * std::pow(q, i) * r.rgb[(ray * 64 + i) * 3 + ch];
      CHECK(res.outputs.colour[ray * 3 + ch] / colour == doctest::Approx(1.0).epsilon(3e-3));
    }
  }
  for (std::size_t k = 0; k < r.sdf.size(); ++k) {
    for (int ch = 0; ch < 3; ++ch)
      CHECK(res.grads.rgb[k * 3 + ch] / (a * std::pow(q, k % 64) * 0.7f) == doctest::Approx(1.0).epsilon(3e-3));
    CHECK(res.grads.sdf[k] == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(res.grads.cos[k] == doctest::Approx(0.0).epsilon(1e-9));
  }
  CHECK(res.grads.inv_s == doctest::Approx(0.0).epsilon(1e-9));
}

TEST_CASE("ray starting inside: all sdf < 0") {
  Rays r(4, 64, 2);
  for (float& s : r.sdf) s = -0.5f - std::fabs(s);
  const auto res = run(r);
  require_finite_result(res);
  // sdf +- |h| <= -0.47 and inv_s = 64: p, c <= e^-30 << 1e-5, so the first sample has
  // alpha = 1 - c / (p + 1e-5) = 1 (float; 1 - 1e-9 in double) and leaves T = 1e-7 behind it:
  // opacity 1 (+1e-7), colour = rgb of the first sample, dL/drgb = gcol there and ~1e-7 after.
  // dalpha/dsdf ~ inv_s c / 1e-5 is 1e-7 at most (4e-14 for these rays), and less for cos and inv_s:
  // those gradients are 0.
  for (std::uint64_t ray = 0; ray < r.rays(); ++ray) {
    CHECK(res.outputs.opacity[ray] == doctest::Approx(1.0).epsilon(1e-6));
    for (int ch = 0; ch < 3; ++ch) {
      CHECK(res.outputs.colour[ray * 3 + ch] == doctest::Approx(r.rgb[ray * 64 * 3 + ch]).epsilon(1e-6));
      CHECK(res.grads.rgb[ray * 64 * 3 + ch] == doctest::Approx(0.7).epsilon(1e-6));
      for (int i = 1; i < 64; ++i) CHECK(res.grads.rgb[(ray * 64 + i) * 3 + ch] == doctest::Approx(0.0).epsilon(1e-6));
    }
  }
  for (std::size_t k = 0; k < r.sdf.size(); ++k) {
    CHECK(res.grads.sdf[k] == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(res.grads.cos[k] == doctest::Approx(0.0).epsilon(1e-9));
  }
  CHECK(res.grads.inv_s == doctest::Approx(0.0).epsilon(1e-9));
}

TEST_CASE("extreme inv_s: 1e6 and 1e-6") {
  for (float inv_s : {1e6f, 1e-6f}) {
    CAPTURE(inv_s);
    Rays r(8, 64, 3);
    r.inv_s = inv_s;
    r.sdf[5] = 0.f;  // exactly on the surface
    for (float anneal : {0.f, 1.f}) {
      CAPTURE(anneal);
      const auto res = run(r, anneal);
      require_finite_result(res);
      // The reference: at 1e6 every sigmoid saturates and all gradients are 0 in both; at 1e-6 the
      // flat sigmoid leaves dalpha/dsdf ~ 1e-11, which float gets only to ~1% (p - c is below its
      // resolution), hence atol = 1e-6.
      check_reference(r, res, anneal, 1e-5, 1e-4, 1e-6);
      // 1e6: a step. Before the surface alpha is the guard's 1e-5 / (1 + 1e-5), at the first sample
      // inside p = 0 and alpha = 1, so opacity = 1 (+ 1e-7 per sample before). 1e-6: p ~ c ~ 1/2 for
      // every sample, alpha = 1e-5 / (1/2 + 1e-5) (+ inv_s |h| ~ 1e-8), compounded as in the miss case;
      // float resolves p - c only to ~1e-7, i.e. ~1% of that alpha.
      const double a = 1e-5 / (0.5 + 1e-5), q = 1 - a + 1e-7, flat = a * (1 - std::pow(q, 64)) / (1 - q);
      for (float o : res.outputs.opacity) {
        if (inv_s > 1.f) {
          CHECK(o == doctest::Approx(1.0).epsilon(1e-5));
        } else {
          CHECK(o / flat == doctest::Approx(1.0).epsilon(1e-2));
        }
      }
    }
  }
}

TEST_CASE("zero-length sections and cos on the kinks") {
  Rays r(6, 32, 4);
  for (std::size_t i = 0; i < r.dist.size(); i += 2) r.dist[i] = 0.f;
  const float kinks[] = {0.f, 1.f, -1.f};
  for (std::size_t i = 0; i < r.cos.size(); ++i) r.cos[i] = kinks[i % 3];
  for (float anneal : {0.f, 0.5f, 1.f}) {
    const auto res = run(r, anneal);
    require_finite_result(res);
    // dist = 0 and cos = 0 or 1 (anneal = 0): iter_cos * dist = 0, so dL/dcos = 0 there.
    for (std::size_t i = 0; i < r.cos.size(); i += 2) CHECK(res.grads.cos[i] == 0.f);
    // Everywhere else: the reference (the kinks take subgradient 0 in both).
    check_reference(r, res, anneal, 1e-5, 1e-4, 1e-7);
  }
}

TEST_CASE("one ray, one sample") {
  Rays r(1, 1, 5);
  r.sdf[0] = 0.f;
  r.cos[0] = -0.5f;
  const auto res = run(r);
  require_finite_result(res);
  const std::vector<double> s{0.0}, c{-0.5}, d(r.dist.begin(), r.dist.end()), rgb(r.rgb.begin(), r.rgb.end());
  const auto ref = volume_render_forward_ref<double>(1, 1, {s, c, d, rgb, 64.0}, 0.5);
  CHECK(res.outputs.opacity[0] == doctest::Approx(ref.opacity[0]).epsilon(1e-5));
  // And the colour and every gradient (|h| = 0.625 dist / 2 ~ 0.35: alpha ~ 1, colour ~ rgb).
  check_reference(r, res, 0.5f, 1e-5, 1e-4, 1e-7);
}

TEST_CASE("NaN/Inf and wrong sizes are rejected by name") {
  Rays r(2, 8, 6);
  r.cos[3] = std::nanf("");
  CHECK_THROWS_WITH_AS(run(r), doctest::Contains("cos"), InputError);
  Rays q(2, 8, 6);
  q.rgb.pop_back();
  CHECK_THROWS_WITH_AS(run(q), doctest::Contains("rgb"), InputError);
  Rays z(2, 8, 6);
  z.inv_s = std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH_AS(run(z), doctest::Contains("inv_s"), InputError);
}

TEST_CASE("chunked dispatches equal one dispatch") {
  Rays r(300, 16, 7);
  const auto a = run(r), b = run(r, 0.5f, 64);
  CHECK(a.outputs.colour == b.outputs.colour);
  CHECK(a.grads.sdf == b.grads.sdf);
  CHECK(a.grads.inv_s == doctest::Approx(b.grads.inv_s).epsilon(1e-4));
}

TEST_CASE("200k rays x 64 samples: GPU == double reference on sampled rays") {
  Rays r(200000, 64, 8);
  const std::uint64_t rays = r.rays();
  const std::vector<float> gc(rays * 3, 0.7f), go(rays, -0.3f);
  VolumeRenderParams p;
  p.cos_anneal = 0.5f;
  gpu::Context& ctx = test::context();
  const auto res = volume_render_with_gradients(ctx, 64, r.inputs(), p, gc, go);
  require_finite_result(res);
  // Timing (device-resident buffers, forward and backward recorded separately).
  {
    const std::uint64_t n = rays * 64;
    gpu::Buffer<float> sdf(ctx, r.sdf, "sdf"), cs(ctx, r.cos, "cos"), dist(ctx, r.dist, "dist"), rgb(ctx, r.rgb, "rgb");
    gpu::Buffer<float> col(ctx, rays * 3, "colour"), op(ctx, rays, "opacity"), gcol(ctx, gc, "gc"), gop(ctx, go, "go");
    gpu::Buffer<float> gs(ctx, n, "gs"), gco(ctx, n, "gco"), grgb(ctx, n * 3, "grgb"), gi(ctx, 1, "gi");
    p.inv_s = r.inv_s;
    const VolumeRenderInputBuffers in{sdf, cs, dist, rgb};
    const auto time = [&](bool backward) {
      const int reps = 5;
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < reps; ++k) {
        gpu::Stream stream(ctx);
        if (backward)
          volume_render_backward(stream, {rays, 64}, p, in, gcol, gop, {gs, gco, grgb, gi});
        else
          volume_render_forward(stream, {rays, 64}, p, in, {col, op});
        stream.submit_and_wait();
      }
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / reps;
    };
    time(false);
    const double f = time(false), b = time(true);
    std::printf("volume_render 200k x 64 on %s: forward %.2f ms, backward %.2f ms\n", ctx.info().name.c_str(), f, b);
  }
  // Sampled rays against the double reference (whole-batch reference for dL/dinv_s).
  std::vector<double> sd(r.sdf.begin(), r.sdf.end()), cd(r.cos.begin(), r.cos.end()), dd(r.dist.begin(), r.dist.end()),
      rd(r.rgb.begin(), r.rgb.end()), gcd(gc.begin(), gc.end()), god(go.begin(), go.end());
  const VolumeRenderInputs<double> in{sd, cd, dd, rd, double(r.inv_s)};
  const auto out = volume_render_forward_ref<double>(rays, 64, in, 0.5);
  const auto g = volume_render_backward_ref<double>(rays, 64, in, 0.5, gcd, god);
  double err_out = 0, err_sdf = 0, err_cos = 0, err_rgb = 0, max_sdf = 0, max_cos = 0;
  for (std::uint64_t k = 0; k < rays * 64; ++k) {
    max_sdf = std::max(max_sdf, std::fabs(g.sdf[k]));
    max_cos = std::max(max_cos, std::fabs(g.cos[k]));
  }
  for (std::uint64_t ray = 0; ray < rays; ray += 97) {
    err_out = std::max(err_out, std::fabs(res.outputs.opacity[ray] - out.opacity[ray]));
    for (int ch = 0; ch < 3; ++ch)
      err_out = std::max(err_out, std::fabs(res.outputs.colour[ray * 3 + ch] - out.colour[ray * 3 + ch]));
    for (std::uint64_t k = ray * 64; k < ray * 64 + 64; ++k) {
      err_sdf = std::max(err_sdf, std::fabs(res.grads.sdf[k] - g.sdf[k]));
      err_cos = std::max(err_cos, std::fabs(res.grads.cos[k] - g.cos[k]));
      for (int ch = 0; ch < 3; ++ch) err_rgb = std::max(err_rgb, std::fabs(res.grads.rgb[k * 3 + ch] - g.rgb[k * 3 + ch]));
    }
  }
  const double err_inv_s = std::fabs(res.grads.inv_s - g.inv_s) / std::max(1e-30, std::fabs(g.inv_s));
  std::printf("200k: max abs err outputs %.3g, rel (inf-norm) sdf %.3g cos %.3g rgb %.3g inv_s %.3g\n", err_out,
              err_sdf / max_sdf, err_cos / max_cos, err_rgb / 0.7, err_inv_s);
  CHECK(err_out < 1e-4);  // outputs are in [0, 1]
  CHECK(err_sdf / max_sdf < 1e-4);
  CHECK(err_cos / max_cos < 1e-4);
  CHECK(err_rgb / 0.7 < 1e-4);
  CHECK(err_inv_s < 1e-3);  // 12.8M float terms, summed by atomics in arbitrary order
}
