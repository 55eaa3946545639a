#include "engine/synth/fur_growth.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::synth {

using body::Region;

namespace {

constexpr float kPi = 3.14159265358979f;

glm::vec3 vertex(const geometry::Mesh& m, std::uint32_t i) { return {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]}; }
glm::vec3 normal(const geometry::Mesh& m, std::uint32_t i) { return {m.normals[3 * i], m.normals[3 * i + 1], m.normals[3 * i + 2]}; }

glm::vec3 any_perpendicular(glm::vec3 n) {
  const glm::vec3 a = std::fabs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(n, a));
}

glm::vec3 rotate_about(glm::vec3 v, glm::vec3 axis, float angle) {
  return v * std::cos(angle) + glm::cross(axis, v) * std::sin(angle) + axis * glm::dot(axis, v) * (1 - std::cos(angle));
}

struct Root {
  glm::vec3 position, normal;
  Region region;
};

// Keeps a point at least `height` above the skin, judged by the nearest body vertex's normal.
struct SkinGuard {
  const geometry::Mesh& body;
  geometry::PointIndex index;
  explicit SkinGuard(const geometry::Mesh& b) : body(b), index(b.positions) {}
  glm::vec3 push_out(glm::vec3 p, float height) const {
    const float q[3] = {p.x, p.y, p.z};
    const auto [i, d2] = index.nearest(q);
    (void)d2;
    const glm::vec3 n = normal(body, i);
    const float above = glm::dot(p - vertex(body, i), n);
    return above < height ? p + (height - above) * n : p;
  }
};

float polyline_length(const std::vector<glm::vec3>& p) {
  float l = 0;
  for (std::size_t k = 1; k < p.size(); ++k) l += glm::distance(p[k], p[k - 1]);
  return l;
}

// Rebuilds the strand segment by segment, pushing each point out of the skin before the next
// segment is added, so a push carries along the rest of the strand instead of kinking it.
void keep_outside(std::vector<glm::vec3>& p, const SkinGuard& guard, float height) {
  glm::vec3 previous_original = p[0];
  for (std::size_t i = 1; i < p.size(); ++i) {
    const glm::vec3 step = p[i] - previous_original;
    previous_original = p[i];
    const float h = height * std::min(1.0f, 4.0f * float(i) / float(p.size()));
    p[i] = guard.push_out(p[i - 1] + step, h);
  }
}

// Scales a strand about its root so that it is exactly `length` long.
void set_length(std::vector<glm::vec3>& p, float length) {
  const float l = polyline_length(p);
  if (l <= 0) return;
  for (std::size_t k = 1; k < p.size(); ++k) p[k] = p[0] + (p[k] - p[0]) * (length / l);
}

}  // namespace

Fur grow_fur(const geometry::Mesh& body, const knowledge::Knowledge& knowledge, const FurStyle& style, const GrowOptions& o) {
  body.validate("body mesh");
  if (body.normals.empty() || body.regions.empty()) throw InputError("body mesh: fur growth needs per-vertex normals and regions");
  if (o.points_per_strand < 2) throw UsageError("points per strand must be at least 2");
  const float unit_per_cm = 1.0f / o.cm_per_unit;
  auto length_of = [&](std::int32_t r) {
    const Region region = static_cast<Region>(r);
    return knowledge.grows_fur(region) ? knowledge.at(region).length_cm * unit_per_cm : 0.0f;
  };

  // Triangles weighted by area / length: short fur is denser, so every region is covered.
  const std::size_t nt = body.triangle_count();
  std::vector<double> cdf(nt + 1, 0.0);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* tri = &body.triangles[3 * t];
    const float area = 0.5f * glm::length(glm::cross(vertex(body, tri[1]) - vertex(body, tri[0]), vertex(body, tri[2]) - vertex(body, tri[0])));
    float inv_len = 0;
    for (int c = 0; c < 3; ++c) {
      const float l = length_of(body.regions[tri[c]]);
      inv_len += l > 0 ? 1.0f / std::max(l, 0.002f * o.torso_length) : 0.0f;
    }
    cdf[t + 1] = cdf[t] + double(area) * inv_len / 3.0;
  }
  if (!(cdf[nt] > 0)) throw InputError("knowledge '" + knowledge.animal + "': no region of the body grows fur");

  std::mt19937_64 rng(o.seed * 0x9E3779B97F4A7C15ull + 7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Root> roots;
  roots.reserve(o.strand_count);
  std::uint64_t attempts = 0;
  while (roots.size() < o.strand_count) {
    if (++attempts > 50ull * o.strand_count + 1000) throw InternalError("fur growth: could not place roots on furred regions");
    const double pick = uni(rng) * cdf[nt];
    const std::size_t t = std::min<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin() - 1, nt - 1);
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const double w[3] = {1 - a - b, a, b};
    const std::uint32_t* tri = &body.triangles[3 * t];
    const int major = int(std::max_element(w, w + 3) - w);
    const std::int32_t region = body.regions[tri[major]];
    if (length_of(region) <= 0) continue;  // the bald side of a border triangle
    Root r{glm::vec3(0), glm::vec3(0), static_cast<Region>(region)};
    for (int c = 0; c < 3; ++c) r.position += float(w[c]) * vertex(body, tri[c]), r.normal += float(w[c]) * normal(body, tri[c]);
    r.normal = glm::length(r.normal) > 0 ? glm::normalize(r.normal) : glm::vec3(0, 1, 0);
    roots.push_back(r);
  }

  const std::uint32_t n = o.strand_count, L = o.points_per_strand;
  const glm::mat3 rotation(o.animal_to_world);
  const glm::vec3 up = glm::normalize(rotation * glm::vec3(0, 1, 0));
  const glm::mat4 world_to_animal = glm::inverse(o.animal_to_world);
  Fur fur;
  fur.strands.points.resize(std::size_t(n) * L * 3);
  fur.strands.regions.resize(n);
  fur.root_colors.resize(n);
  fur.root_normals.resize(n);
  std::vector<float> lengths(n);
  const SkinGuard guard(body);

  // Per-strand random numbers drawn up front so the result does not depend on thread timing.
  struct Draw { float length, turn, lift, phase_wave, phase_curl, bend[4], color; };
  std::vector<Draw> draws(n);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  for (auto& d : draws) {
    d.length = 1.0f + style.length_jitter * std::clamp(gauss(rng), -2.5f, 2.5f);
    d.turn = style.direction_noise_deg * kPi / 180.0f * std::clamp(gauss(rng), -2.5f, 2.5f);
    d.lift = style.lift_jitter_deg * std::clamp(gauss(rng), -2.0f, 2.0f);
    d.phase_wave = float(uni(rng)) * 2 * kPi, d.phase_curl = float(uni(rng)) * 2 * kPi;
    for (float& b : d.bend) b = style.bend_noise * gauss(rng);
    d.color = 1.0f + 0.12f * std::clamp(gauss(rng), -2.0f, 2.0f);
  }

  parallel_for(n, [&](std::size_t s0, std::size_t s1) {
    std::vector<glm::vec3> p(L);
    for (std::size_t s = s0; s < s1; ++s) {
      const Root& root = roots[s];
      const Draw& d = draws[s];
      const knowledge::RegionKnowledge& k = knowledge.at(root.region);
      const float length = std::max(k.length_cm * unit_per_cm * d.length, 1e-6f);
      const glm::vec3 nrm = root.normal;
      const glm::vec3 growth = rotation * k.direction;
      glm::vec3 tangent = growth - glm::dot(growth, nrm) * nrm;
      tangent = glm::length(tangent) > 1e-3f ? glm::normalize(tangent) : any_perpendicular(nrm);
      tangent = rotate_about(tangent, nrm, d.turn);
      const glm::vec3 side = glm::cross(nrm, tangent);
      const float lift0 = std::clamp(style.lift_deg + d.lift, 5.0f, 85.0f) * kPi / 180.0f;
      const bool mane = root.region == Region::mane;
      const float wave = (mane ? style.mane_wave_amplitude : style.wave_amplitude) * length;
      const float seg = length / float(L - 1);
      // Longer fur sags more; the sag is measured in torso lengths so all animals compare.
      const float sag = style.gravity * std::min(1.0f, length / (0.05f * o.torso_length));
      p[0] = root.position;
      for (std::uint32_t i = 1; i < L; ++i) {
        const float t = float(i - 1) / float(L - 1);
        const float lift = lift0 * (1.0f - (1.0f - style.lift_tip_fraction) * t);
        glm::vec3 dir = std::cos(lift) * tangent + std::sin(lift) * nrm;
        const float bend = d.bend[0] * std::sin(kPi * t) + d.bend[1] * std::sin(2 * kPi * t);
        dir += bend * side + (d.bend[2] * std::sin(kPi * t)) * nrm - sag * t * up;
        dir = glm::normalize(dir);
        p[i] = p[i - 1] + seg * dir;
      }
      // Wave and curl as offsets that grow from the root.
      for (std::uint32_t i = 1; i < L; ++i) {
        const float t = float(i) / float(L - 1);
        glm::vec3 offset = wave * t * std::sin(2 * kPi * style.wave_periods * t + d.phase_wave) * side;
        if (style.curl_radius > 0) {
          const float a = 2 * kPi * style.curl_turns * t + d.phase_curl;
          offset += style.curl_radius * length * t * (std::cos(a) * side + std::sin(a) * nrm);
        }
        p[i] += offset;
      }
      set_length(p, length);
      keep_outside(p, guard, 0.02f * length);
      set_length(p, length);
      float* out = &fur.strands.points[s * L * 3];
      for (std::uint32_t i = 0; i < L; ++i) out[3 * i] = p[i].x, out[3 * i + 1] = p[i].y, out[3 * i + 2] = p[i].z;
      lengths[s] = length;
      fur.strands.regions[s] = std::uint16_t(root.region);
      fur.root_normals[s] = nrm;
      const glm::vec3 animal_pos(world_to_animal * glm::vec4(root.position, 1.0f));
      const glm::vec3 animal_nrm(world_to_animal * glm::vec4(nrm, 0.0f));
      fur.root_colors[s] = glm::clamp(d.color * coat_color(o.animal, root.region, animal_pos, animal_nrm, o.torso_length),
                                      glm::vec3(0), glm::vec3(1));
    }
  });

  // Clumping: every strand bends its tip towards the nearest clump centre's strand of the same
  // region, more strongly towards the tip.
  if (style.clump_strength > 0 && n > 1) {
    const std::uint32_t centres = std::max<std::uint32_t>(1, std::uint32_t(float(n) / style.strands_per_clump));
    std::vector<float> centre_roots(std::size_t(centres) * 3);
    for (std::uint32_t c = 0; c < centres; ++c) {
      const std::size_t s = std::size_t(c) * n / centres;  // roots are in random order already
      for (int a = 0; a < 3; ++a) centre_roots[3 * c + a] = fur.strands.points[s * L * 3 + a];
    }
    const geometry::PointIndex index(centre_roots);
    const std::vector<float> before = fur.strands.points;
    parallel_for(n, [&](std::size_t s0, std::size_t s1) {
      std::vector<glm::vec3> p(L);
      for (std::size_t s = s0; s < s1; ++s) {
        const float* mine = &before[s * L * 3];
        const auto [c, d2] = index.nearest(mine);
        const std::size_t cs = std::size_t(c) * n / centres;
        if (cs == s || fur.strands.regions[cs] != fur.strands.regions[s] || std::sqrt(d2) > 0.5f * lengths[s]) continue;
        const float* theirs = &before[cs * L * 3];
        for (std::uint32_t i = 0; i < L; ++i) {
          const float t = float(i) / float(L - 1);
          const float pull = style.clump_strength * t * std::sqrt(t);
          const glm::vec3 a(mine[3 * i], mine[3 * i + 1], mine[3 * i + 2]), b(theirs[3 * i], theirs[3 * i + 1], theirs[3 * i + 2]);
          p[i] = a + pull * (b - a);
        }
        keep_outside(p, guard, 0.0f);
        set_length(p, lengths[s]);
        float* out = &fur.strands.points[s * L * 3];
        for (std::uint32_t i = 0; i < L; ++i) out[3 * i] = p[i].x, out[3 * i + 1] = p[i].y, out[3 * i + 2] = p[i].z;
      }
    });
  }
  fur.strands.offsets.resize(n + 1);
  for (std::uint32_t s = 0; s <= n; ++s) fur.strands.offsets[s] = s * L;
  return fur;
}

}  // namespace nf::synth
