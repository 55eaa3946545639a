#include "engine/synth/strand_renderer.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/color.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::synth {

namespace {

constexpr unsigned kBodyGeometry = 0, kStrandGeometry = 1;

float srgb_encode(float linear) { return color::linear_to_srgb(linear); }

}  // namespace

// Roots sit in the coat's shadow; tips catch the light.
glm::vec3 strand_albedo(glm::vec3 base, float along) { return base * (0.45f + 0.55f * std::sqrt(std::clamp(along, 0.f, 1.f))); }

namespace {

// A per-pixel hash for the jitter of stratified samples (deterministic, no shared RNG state).
float hash01(std::uint32_t x) {
  x ^= x >> 16, x *= 0x7feb352dU, x ^= x >> 15, x *= 0x846ca68bU, x ^= x >> 16;
  return float(x >> 8) * (1.0f / 16777216.0f);
}

struct Light {
  glm::vec3 direction;  // towards the light
  float intensity;
};

}  // namespace

struct StrandRenderer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  geometry::Mesh body;
  std::vector<glm::vec3> body_colors;
  std::vector<glm::vec4> curve_points;  // xyz radius, render_points per strand
  std::vector<glm::vec3> strand_colors;
  std::uint32_t points_per_strand = 0;
  RenderOptions options;
  std::vector<Light> lights;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  // The unit tangent of the strand segment a hit lies on.
  glm::vec3 hair_tangent(const RTCRayHit& hit) const {
    const std::uint32_t segments = points_per_strand - 1;
    const std::uint32_t strand = hit.hit.primID / segments, k = hit.hit.primID % segments;
    const glm::vec4 a = curve_points[strand * points_per_strand + k], b = curve_points[strand * points_per_strand + k + 1];
    const glm::vec3 t = glm::vec3(b) - glm::vec3(a);
    return glm::length(t) > 0 ? glm::normalize(t) : glm::vec3(0, 1, 0);
  }

  glm::vec3 shade_hair(const RTCRayHit& hit, glm::vec3 view) const {
    const std::uint32_t segments = points_per_strand - 1;
    const std::uint32_t strand = hit.hit.primID / segments, k = hit.hit.primID % segments;
    const glm::vec3 t = hair_tangent(hit);
    const float along = (float(k) + hit.hit.u) / float(segments);
    const glm::vec3 base = strand_colors.empty() ? glm::vec3(0.5f) : strand_colors[strand];
    const glm::vec3 albedo = strand_albedo(base, along);
    glm::vec3 c = 0.25f * albedo;
    const float tv = glm::dot(t, view), sin_v = std::sqrt(std::max(0.0f, 1 - tv * tv));
    for (const Light& l : lights) {
      const float tl = glm::dot(t, l.direction), sin_l = std::sqrt(std::max(0.0f, 1 - tl * tl));
      switch (options.shading) {
        case HairShading::KajiyaKay: {
          const float spec = std::pow(std::max(0.0f, sin_l * sin_v - tl * tv), 40.0f);
          c += l.intensity * (albedo * sin_l * 0.8f + glm::vec3(0.12f) * spec);
          break;
        }
        case HairShading::TwoLobe: {
          // Longitudinal angles from the normal plane; the mirror direction has theta_h = 0.
          const float half = 0.5f * (std::asin(std::clamp(tl, -1.f, 1.f)) + std::asin(std::clamp(tv, -1.f, 1.f)));
          const auto lobe = [&](float shift_deg, float width_deg) {
            const float d = (half - glm::radians(shift_deg)) / glm::radians(width_deg);
            return std::exp(-0.5f * d * d);
          };
          c += l.intensity * (albedo * sin_l * 0.6f + glm::vec3(0.22f) * lobe(-5.f, 6.f) + albedo * 0.5f * lobe(7.5f, 10.f));
          break;
        }
        case HairShading::Matte:
          c += l.intensity * albedo * sin_l * 0.85f;
          break;
      }
    }
    return c;
  }

  glm::vec3 shade_body(const RTCRayHit& hit, glm::vec3 view) const {
    const std::uint32_t* tri = &body.triangles[3 * hit.hit.primID];
    const float w[3] = {1 - hit.hit.u - hit.hit.v, hit.hit.u, hit.hit.v};
    glm::vec3 n(0), albedo(0);
    for (int c = 0; c < 3; ++c) {
      n += w[c] * glm::vec3(body.normals[3 * tri[c]], body.normals[3 * tri[c] + 1], body.normals[3 * tri[c] + 2]);
      albedo += w[c] * (body_colors.empty() ? glm::vec3(0.5f) : body_colors[tri[c]]);
    }
    n = glm::length(n) > 0 ? glm::normalize(n) : glm::vec3(0, 1, 0);
    if (glm::dot(n, view) < 0) n = -n;
    glm::vec3 c = 0.2f * albedo;
    for (const Light& l : lights) {
      const glm::vec3 h = glm::normalize(l.direction + view);
      c += l.intensity * (albedo * std::max(0.0f, glm::dot(n, l.direction)) + glm::vec3(0.08f) * std::pow(std::max(0.0f, glm::dot(n, h)), 60.0f));
    }
    return c;
  }
};

HairShading hair_shading_from(const std::string& name) {
  if (name == "kajiya-kay") return HairShading::KajiyaKay;
  if (name == "two-lobe") return HairShading::TwoLobe;
  if (name == "matte") return HairShading::Matte;
  throw UsageError("hair shading: unknown '" + name + "' (kajiya-kay, two-lobe, matte)");
}

const std::vector<std::string>& hair_shading_names() {
  static const std::vector<std::string> names{"kajiya-kay", "two-lobe", "matte"};
  return names;
}

StrandRenderer::StrandRenderer(const geometry::Mesh& body, const BodyLook& body_look, const io::StrandSet& strands,
                               const StrandLook& look, const RenderOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  m.body = body;
  m.body_colors = body_look.vertex_colors;
  m.strand_colors = look.root_colors;
  const bool has_body = body.triangle_count() > 0;  // strands alone are fine (e.g. silhouettes)
  if (has_body && m.body.normals.size() != body.positions.size()) throw InputError("renderer: the body mesh needs vertex normals");
  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw InternalError("Embree: rtcNewDevice failed (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  m.scene = rtcNewScene(m.device);
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_MEDIUM);

  if (has_body) {
    RTCGeometry mesh = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), body.vertex_count()));
    std::copy(body.positions.begin(), body.positions.end(), vb);
    unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), body.triangle_count()));
    std::copy(body.triangles.begin(), body.triangles.end(), ib);
    rtcCommitGeometry(mesh);
    rtcAttachGeometryByID(m.scene, mesh, kBodyGeometry);
    rtcReleaseGeometry(mesh);
  }

  const std::uint32_t n = strands.strand_count();
  if (n > 0) {
    // Each strand is resampled to render_points points evenly spaced in its own point indices.
    const std::uint32_t rp = std::max<std::uint32_t>(2, options.render_points);
    m.points_per_strand = rp;
    m.curve_points.resize(std::size_t(n) * rp);
    parallel_for(n, [&](std::size_t s0, std::size_t s1) {
      for (std::size_t s = s0; s < s1; ++s) {
        const std::uint32_t first = strands.offsets[s], count = strands.offsets[s + 1] - first;
        for (std::uint32_t k = 0; k < rp; ++k) {
          const float x = count > 1 ? float(k) * float(count - 1) / float(rp - 1) : 0.0f;
          const std::uint32_t i = std::min<std::uint32_t>(std::uint32_t(x), count > 1 ? count - 2 : 0);
          const float f = count > 1 ? x - float(i) : 0.0f;
          const std::uint32_t j = count > 1 ? i + 1 : i;
          glm::vec3 p;
          for (int c = 0; c < 3; ++c) p[c] = (1 - f) * strands.points[3 * (first + i) + c] + f * strands.points[3 * (first + j) + c];
          m.curve_points[s * rp + k] = glm::vec4(p, look.radius);
        }
      }
    });
    RTCGeometry curves = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
    glm::vec4* cv = static_cast<glm::vec4*>(rtcSetNewGeometryBuffer(curves, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, sizeof(glm::vec4), m.curve_points.size()));
    std::copy(m.curve_points.begin(), m.curve_points.end(), cv);
    const std::size_t segments = std::size_t(n) * (rp - 1);
    unsigned* ci = static_cast<unsigned*>(rtcSetNewGeometryBuffer(curves, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), segments));
    for (std::size_t s = 0, q = 0; s < n; ++s)
      for (std::uint32_t k = 0; k + 1 < rp; ++k) ci[q++] = unsigned(s * rp + k);
    rtcCommitGeometry(curves);
    rtcAttachGeometryByID(m.scene, curves, kStrandGeometry);
    rtcReleaseGeometry(curves);
  }
  rtcCommitScene(m.scene);
  if (rtcGetDeviceError(m.device) != RTC_ERROR_NONE)
    throw InternalError("Embree: building the scene failed (error " + std::to_string(int(rtcGetDeviceError(m.device))) + ")");
  m.lights = {{glm::normalize(glm::vec3(0.4f, 1.0f, 0.5f)), 0.9f}, {glm::normalize(glm::vec3(-0.6f, 0.3f, -0.4f)), 0.35f}};
}

StrandRenderer::~StrandRenderer() = default;

Rendered StrandRenderer::render(const io::Camera& camera) const {
  const Impl& m = *impl_;
  const std::uint32_t w = camera.width, h = camera.height, s = std::max<std::uint32_t>(1, m.options.samples_per_axis);
  Rendered out;
  out.rgb = {w, h, 3, std::vector<float>(std::size_t(w) * h * 3)};
  out.coverage = {w, h, 1, std::vector<float>(std::size_t(w) * h)};
  const bool orient = m.options.true_orientation;
  if (orient) out.orientation = {w, h, 2, std::vector<float>(std::size_t(w) * h * 2)};
  const glm::dmat4& c2w = camera.camera_to_world;
  const glm::vec3 origin(c2w[3]);
  const glm::mat3 rot(c2w);
  parallel_for(h, [&](std::size_t y0, std::size_t y1) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t y = y0; y < y1; ++y)
      for (std::uint32_t x = 0; x < w; ++x) {
        glm::vec3 sum(0);
        glm::dvec2 doubled(0);  // the strand samples' doubled-angle vectors, summed
        std::uint32_t hits = 0;
        const std::uint32_t pixel = std::uint32_t(y) * w + x;
        for (std::uint32_t sy = 0; sy < s; ++sy)
          for (std::uint32_t sx = 0; sx < s; ++sx) {
            const std::uint32_t id = (pixel * s + sy) * s + sx;
            // Pixel (x, y) covers [x, x+1) x [y, y+1), as Camera::project counts.
            const double u = x + (sx + hash01(2 * id)) / s, v = y + (sy + hash01(2 * id + 1)) / s;
            const glm::vec3 d_cam(float((u - camera.cx) / camera.fx), float(-(v - camera.cy) / camera.fy), -1.0f);
            const glm::vec3 dir = glm::normalize(rot * d_cam);
            RTCRayHit rh{};
            rh.ray.org_x = origin.x, rh.ray.org_y = origin.y, rh.ray.org_z = origin.z;
            rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
            rh.ray.tnear = 0.0f, rh.ray.tfar = std::numeric_limits<float>::infinity();
            rh.ray.mask = 0xFFFFFFFFu, rh.ray.flags = 0;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(m.scene, &context, &rh);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
              sum += backdrop_color(m.options.backdrop, origin, dir);
              continue;
            }
            ++hits;
            sum += rh.hit.geomID == kStrandGeometry ? m.shade_hair(rh, -dir) : m.shade_body(rh, -dir);
            if (orient && rh.hit.geomID == kStrandGeometry) {
              // The tangent's direction on screen: the hit and a point a little along the strand, projected.
              const glm::dvec3 at = glm::dvec3(origin) + double(rh.ray.tfar) * glm::dvec3(dir);
              const glm::dvec3 a = camera.project(at), b = camera.project(at + 1e-3 * double(rh.ray.tfar) * glm::dvec3(m.hair_tangent(rh)));
              if (b.x != a.x || b.y != a.y) {
                const double theta = orient::orientation_of_direction(b.x - a.x, b.y - a.y);
                doubled += glm::dvec2(std::cos(2 * theta), std::sin(2 * theta));
              }
            }
          }
        const float inv = 1.0f / float(s * s);
        for (int c = 0; c < 3; ++c) out.rgb.pixels[3 * std::size_t(pixel) + c] = srgb_encode(sum[c] * inv);
        out.coverage.pixels[pixel] = float(hits) * inv;
        if (orient) {
          double theta = 0.5 * std::atan2(doubled.y, doubled.x);
          if (theta < 0) theta += orient::kPi;
          out.orientation.pixels[2 * std::size_t(pixel)] = float(theta);
          out.orientation.pixels[2 * std::size_t(pixel) + 1] = float(glm::length(doubled) * inv);
        }
      }
  }, 1);  // a row of a few hundred pixels, each traced s x s times
  return out;
}

}  // namespace nf::synth
