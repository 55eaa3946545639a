#include "engine/fur/strand_shapes.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/core/error.hpp"

namespace nf::fur {
namespace {

constexpr float kPi = 3.14159265358979f;

// Uniform in [a, b) from the generator's bits, identical on every standard library.
struct Draw {
  std::mt19937_64 rng;
  float uniform(float a, float b) { return a + (b - a) * float(double(rng() >> 11) * (1.0 / 9007199254740992.0)); }
  bool chance(float p) { return uniform(0, 1) < p; }
};

struct Shape {
  float lift = 0.5f;         // angle above the skin at the root, radians
  float tip_fraction = 1;    // the tip's lift as a fraction of the root's (below 0: towards the skin)
  float lie_power = 1;       // how late along the strand it lies down
  float heading = 0;         // direction on the skin, radians from T
  float drift = 0;           // heading change root to tip
  float bend[2][3] = {};     // smooth random bends: amplitude, frequency, phase (lift, heading)
  float wave = 0, wave_periods = 1, wave_phase = 0;  // planar wave: angular amplitude, periods
  float curl = 0, curl_turns = 0, curl_phase = 0;    // helix: cone angle, turns
  float sag = 0;
  glm::vec3 gravity{0, 0, -1};
};

Shape draw_shape(Draw& d, StrandStyle style) {
  Shape s;
  s.heading = d.uniform(0, 2 * kPi);
  s.lift = d.uniform(0, 1) < 0.15f ? d.uniform(1.0f, 1.5708f) : d.uniform(0.0f, 1.1f);
  s.tip_fraction = d.uniform(-0.3f, 1.3f);
  s.lie_power = d.uniform(0.6f, 2.5f);
  s.drift = d.chance(0.5f) ? d.uniform(-0.9f, 0.9f) : 0.0f;
  for (auto& b : s.bend)
    if (d.chance(0.6f)) b[0] = d.uniform(0.0f, 0.35f), b[1] = d.uniform(0.3f, 2.0f), b[2] = d.uniform(0, 2 * kPi);
  const bool wavy = style == StrandStyle::Wavy || (style == StrandStyle::Any && d.chance(0.35f));
  const bool curly = style == StrandStyle::Curly || (style == StrandStyle::Any && d.chance(0.2f));
  const bool sagging = style == StrandStyle::Sagging || (style == StrandStyle::Any && d.chance(0.35f));
  if (style == StrandStyle::Straight) {
    s.tip_fraction = d.uniform(0.85f, 1.1f), s.drift = 0;
    for (auto& b : s.bend) b[0] *= 0.2f;
  }
  if (style == StrandStyle::LyingDown) s.lift = d.uniform(0.05f, 0.9f), s.tip_fraction = d.uniform(-0.3f, 0.4f);
  if (wavy) {
    s.wave_periods = d.uniform(0.5f, 5.0f);
    // An amplitude of up to 8 % of the length: the angle that gives it at this frequency.
    const float amplitude = d.uniform(0.005f, 0.08f);
    s.wave = std::min(1.2f, 2 * kPi * s.wave_periods * amplitude);
    s.wave_phase = d.uniform(0, 2 * kPi);
  }
  if (curly) {
    s.curl_turns = d.uniform(1.0f, 8.0f);
    const float radius = d.uniform(0.01f, 0.08f);  // of the length
    s.curl = std::min(1.3f, std::atan(2 * kPi * radius * s.curl_turns));
    s.curl_phase = d.uniform(0, 2 * kPi);
  }
  if (sagging) {
    s.sag = d.uniform(0.1f, 1.5f);
    // Gravity mostly into the skin's side of the frame, but any way the skin can be turned.
    const float a = d.uniform(0, 2 * kPi), z = d.uniform(-1.0f, 0.3f);
    s.gravity = glm::normalize(glm::vec3(std::sqrt(1 - z * z) * std::cos(a), std::sqrt(1 - z * z) * std::sin(a), z));
  }
  return s;
}

glm::vec3 any_perpendicular(const glm::vec3& v) {
  const glm::vec3 other = std::fabs(v.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  return glm::normalize(glm::cross(v, other));
}

void build_strand(const Shape& s, float* out) {
  glm::vec3 p(0.0f);
  out[0] = out[1] = out[2] = 0;
  const float step = 1.0f / float(kStrandSegments);
  for (std::uint32_t i = 0; i < kStrandSegments; ++i) {
    const float t = (float(i) + 0.5f) * step;
    float lift = s.lift * (1 + (s.tip_fraction - 1) * std::pow(t, s.lie_power));
    float heading = s.heading + s.drift * t;
    lift += s.bend[0][0] * std::sin(2 * kPi * s.bend[0][1] * t + s.bend[0][2]);
    heading += s.bend[1][0] * std::sin(2 * kPi * s.bend[1][1] * t + s.bend[1][2]);
    lift += s.wave * std::sin(2 * kPi * s.wave_periods * t + s.wave_phase);
    glm::vec3 d(std::cos(lift) * std::cos(heading), std::cos(lift) * std::sin(heading), std::sin(lift));
    if (s.curl > 0) {  // precess around the base direction: a helix about the strand's path
      const glm::vec3 u = any_perpendicular(d), v = glm::cross(d, u);
      const float a = 2 * kPi * s.curl_turns * t + s.curl_phase;
      d = std::cos(s.curl) * d + std::sin(s.curl) * (std::cos(a) * u + std::sin(a) * v);
    }
    if (s.sag > 0) d = glm::normalize(d + s.sag * t * s.gravity);
    p += d * step;
    out[3 * (i + 1) + 0] = p.x, out[3 * (i + 1) + 1] = p.y, out[3 * (i + 1) + 2] = p.z;
  }
}

}  // namespace

const std::vector<StrandStyle>& strand_styles() {
  static const std::vector<StrandStyle> styles{StrandStyle::Straight, StrandStyle::LyingDown, StrandStyle::Wavy,
                                               StrandStyle::Curly, StrandStyle::Sagging};
  return styles;
}

std::string style_name(StrandStyle style) {
  switch (style) {
    case StrandStyle::Straight: return "straight";
    case StrandStyle::LyingDown: return "lying_down";
    case StrandStyle::Wavy: return "wavy";
    case StrandStyle::Curly: return "curly";
    case StrandStyle::Sagging: return "sagging";
    case StrandStyle::Any: return "any";
  }
  return "?";
}

std::vector<float> generate_strands(std::uint32_t count, std::uint64_t seed, StrandStyle style) {
  std::vector<float> out(std::size_t(count) * kStrandPoints * 3);
  Draw d{std::mt19937_64(seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull)};
  for (std::uint32_t k = 0; k < count; ++k) build_strand(draw_shape(d, style), &out[std::size_t(k) * kStrandPoints * 3]);
  return out;
}

bool strand_in_frame(const float* points, std::uint32_t count, const glm::vec3& root, const glm::vec3& t,
                     const glm::vec3& b, const glm::vec3& n, float* out) {
  if (count < 2) return false;
  std::vector<glm::vec3> local(count);
  std::vector<float> arc(count, 0.0f);
  for (std::uint32_t i = 0; i < count; ++i) {
    const glm::vec3 q = glm::vec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]) - root;
    local[i] = {glm::dot(q, t), glm::dot(q, b), glm::dot(q, n)};
    if (i) arc[i] = arc[i - 1] + glm::distance(local[i], local[i - 1]);
  }
  const float length = arc.back();
  if (!(length > 0) || !std::isfinite(length)) return false;
  std::uint32_t j = 0;
  for (std::uint32_t k = 0; k < kStrandPoints; ++k) {
    const float s = length * float(k) / float(kStrandSegments);
    while (j + 2 < count && arc[j + 1] < s) ++j;
    const float span = arc[j + 1] - arc[j];
    const float w = span > 0 ? std::clamp((s - arc[j]) / span, 0.0f, 1.0f) : 0.0f;
    const glm::vec3 p = ((1 - w) * local[j] + w * local[j + 1]) / length;
    out[3 * k] = p.x, out[3 * k + 1] = p.y, out[3 * k + 2] = p.z;
  }
  return true;
}

PointError point_error(const std::vector<float>& predicted, const std::vector<float>& truth) {
  NF_CHECK(predicted.size() == truth.size() && truth.size() % (3 * kStrandPoints) == 0, "point_error: sizes differ");
  const std::size_t strands = truth.size() / (3 * kStrandPoints);
  std::vector<double> per(strands);
  for (std::size_t s = 0; s < strands; ++s) {
    double sum = 0;
    for (std::uint32_t k = 0; k < kStrandPoints; ++k) {
      const std::size_t i = (s * kStrandPoints + k) * 3;
      const double dx = predicted[i] - truth[i], dy = predicted[i + 1] - truth[i + 1], dz = predicted[i + 2] - truth[i + 2];
      sum += std::sqrt(dx * dx + dy * dy + dz * dz);
    }
    per[s] = sum / kStrandPoints;
  }
  PointError e;
  for (double v : per) e.mean += v;
  e.mean /= double(std::max<std::size_t>(1, strands));
  if (!per.empty()) {
    std::sort(per.begin(), per.end());
    e.p95 = per[std::min(per.size() - 1, std::size_t(0.95 * double(per.size())))];
  }
  return e;
}

}  // namespace nf::fur
