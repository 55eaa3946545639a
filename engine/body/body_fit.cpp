#include "engine/body/body_fit.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "engine/body/fit_regularisers.hpp"
#include "engine/body/posing.hpp"
#include "engine/body/quadruped.hpp"
#include "engine/body/region_transfer.hpp"
#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/geometry/surface_sampling.hpp"
#include "engine/nn/adam_ref.hpp"

namespace nf::body {
namespace {

// A fit whose mean two-way distance exceeds this share of the target's RMS radius is not a
// quadruped's (measured on the synthetic animals: good fits of M_NeuS stay below 0.05).
constexpr double kLowConfidence = 0.08;

glm::dvec3 at(const std::vector<float>& v, std::size_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }

// Points drawn on the target in the fit frame.
struct Target {
  geometry::Mesh mesh;  // fit frame
  glm::dmat4 fit_to_world{1.0};
  double radius = 1.0;  // RMS radius in world units
};

Target normalise_target(const geometry::Mesh& world, const std::string& source) {
  world.validate(source);
  if (world.triangle_count() == 0) throw InputError(source + ": the mesh has no faces; the body fit needs a surface");
  geometry::Mesh mesh = world;
  const std::size_t components = geometry::keep_largest_component(mesh);
  if (components > 1) {
    const double kept = double(mesh.triangle_count()) / double(world.triangle_count());
    if (kept < 0.75)  // floaters are small; two large parts are two things, not one animal
      throw InputError(source + ": the surface falls into " + std::to_string(components) + " parts and the largest holds only " +
                       std::to_string(int(100 * kept)) + " % of the faces; the body fit needs one animal");
    log::warn("body: ", source, " has ", components, " disconnected parts; fitting the largest (", int(100 * kept),
              " % of the faces)");
  }
  const geometry::SurfaceSamples s = geometry::sample_surface(mesh, 50000, 7);
  if (s.points.empty()) throw InputError(source + ": the surface has no area; the body fit needs a surface");
  glm::dvec3 centre(0.0);
  const std::size_t n = s.points.size() / 3;
  for (std::size_t i = 0; i < n; ++i) centre += at(s.points, i);
  centre /= double(n);
  double r2 = 0;
  for (std::size_t i = 0; i < n; ++i) r2 += glm::dot(at(s.points, i) - centre, at(s.points, i) - centre);
  Target t;
  t.radius = std::sqrt(r2 / double(n));
  if (!(t.radius > 0) || !std::isfinite(t.radius)) throw InputError(source + ": the surface has no extent");
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    const glm::dvec3 p = (at(mesh.positions, i) - centre) / t.radius;
    for (int c = 0; c < 3; ++c) mesh.positions[3 * i + std::size_t(c)] = float(p[c]);
  }
  t.mesh = std::move(mesh);
  t.fit_to_world = glm::dmat4(t.radius);
  t.fit_to_world[3] = glm::dvec4(centre, 1.0);
  return t;
}

glm::dvec3 axis_angle(const glm::dmat3& r) {
  const double c = std::clamp((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0, -1.0, 1.0), angle = std::acos(c);
  if (angle < 1e-9) return glm::dvec3(0.0);
  if (angle > M_PI - 1e-6) {  // near pi: R + I = 2 a a^T; its largest column is the axis (up to sign)
    const glm::dmat3 s = r + glm::dmat3(1.0);
    int k = 0;
    for (int col = 1; col < 3; ++col)
      if (s[col][col] > s[k][k]) k = col;
    return angle * glm::normalize(s[k]);
  }
  const glm::dvec3 axis(r[1][2] - r[2][1], r[2][0] - r[0][2], r[0][1] - r[1][0]);
  return angle * axis / (2.0 * std::sin(angle));
}

// Principal axes (unit, by decreasing variance) of points projected off `up` (or all three when
// up is zero).
std::vector<glm::dvec3> principal_axes(const std::vector<float>& points, const glm::dvec3& up) {
  glm::dmat3 cov(0.0);
  const std::size_t n = points.size() / 3;
  for (std::size_t i = 0; i < n; ++i) {
    glm::dvec3 p = at(points, i);
    p -= glm::dot(p, up) * up;
    cov += glm::outerProduct(p, p);
  }
  // Power iteration with deflation: three symmetric 3x3 eigenvectors, plenty accurate here.
  std::vector<glm::dvec3> axes;
  glm::dmat3 m = cov;
  for (int k = 0; k < 3; ++k) {
    glm::dvec3 v = glm::normalize(glm::dvec3(0.3 + k, 1.0 - 0.2 * k, 0.7));
    double lambda = 0;
    for (int it = 0; it < 200; ++it) {
      glm::dvec3 w = m * v;
      for (const glm::dvec3& a : axes) w -= glm::dot(w, a) * a;
      lambda = glm::length(w);
      if (lambda < 1e-15) break;
      v = w / lambda;
    }
    if (lambda < 1e-15) {  // degenerate: a unit vector orthogonal to up and to the axes found
      std::vector<glm::dvec3> taken = axes;
      if (glm::length(up) > 0) taken.push_back(up);
      for (const glm::dvec3 trial : {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}) {
        v = trial;
        for (const glm::dvec3& a : taken) v -= glm::dot(v, a) * a;
        if (glm::length(v) > 0.1) break;
      }
      v = glm::normalize(v);
    }
    axes.push_back(v);
    m -= lambda * glm::outerProduct(v, v);
  }
  return axes;
}

// The tail's first joint: the first joint named "tail" (any case) whose parent is not; -1 without one.
int tail_root(const BodyModel& model) {
  const auto is_tail = [&](int k) {
    std::string n = model.joint_names[std::size_t(k)];
    std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return n.find("tail") != std::string::npos;
  };
  for (std::size_t k = 0; k < model.joint_count(); ++k)
    if (is_tail(int(k)) && (model.parents[k] < 0 || !is_tail(model.parents[k]))) return int(k);
  return -1;
}

// The vertices skinned (by their first influence) to `root` or to a joint below it.
std::vector<bool> vertices_below(const BodyModel& model, int root) {
  std::vector<bool> below(model.joint_count(), false);
  if (root >= 0) below[std::size_t(root)] = true;
  for (std::size_t k = 0; k < model.joint_count(); ++k)  // parents come before their children
    if (model.parents[k] >= 0 && below[std::size_t(model.parents[k])]) below[k] = true;
  std::vector<bool> out(model.vertex_count());
  for (std::size_t i = 0; i < model.vertex_count(); ++i) out[i] = below[model.skin_joints[i * kSkinInfluences]];
  return out;
}

class Fitter {
 public:
  Fitter(const BodyModel& model, const Target& target, const BodyFitOptions& o)
      : model_(model), target_(target), o_(o), layout_(PoseLayout::of(model, true)), topology_(model.triangles, model.vertex_count()) {
    // Ears fold: a beagle's hang 140 degrees from a cat's upright ones; a tail hangs along the hind
    // legs or stands over the back, 90 degrees from the template's at its root. Every other joint
    // keeps the common limit.
    const int tail = tail_root(model);
    for (std::size_t k = 0; k < model.joint_count(); ++k) {
      const std::string& name = model.joint_names[k];
      const bool turns_freely = ear_joint(name) || int(k) == tail;
      free_.push_back(turns_freely);
      limits_.push_back(turns_freely ? std::max(o.max_joint_angle, 2.8) : o.max_joint_angle);
    }
    const int length = model.shape_index("torso_length"), girth = model.shape_index("torso_girth");
    if (length >= 0 && girth >= 0 && o.min_torso_aspect > 0)
      torso_ = {layout_.shape_begin() + std::size_t(length), layout_.shape_begin() + std::size_t(girth)};
  }

  // Keeps the torso's length over its girth (1 + beta each) at least min_torso_aspect of the
  // template's, moving both coefficients alike in log space.
  void bound_torso(std::vector<double>& x) const {
    const std::optional<double> excess = torso_excess(x);
    if (!excess || !(*excess < 0)) return;  // within the bound (or a NaN, which the loss reports)
    const double half = -0.5 * *excess;
    x[torso_->first] = (1.0 + x[torso_->first]) * std::exp(half) - 1.0;
    x[torso_->second] = (1.0 + x[torso_->second]) * std::exp(-half) - 1.0;
  }
  // Within 2 % of the bound: the chamfer presses the torso against it, and the last Adam step may
  // leave it a little inside.
  bool torso_at_bound(const std::vector<double>& x) const {
    const std::optional<double> excess = torso_excess(x);
    return excess && *excess <= 0.02;
  }

  struct StepResult {
    double loss = 0, chamfer = 0;  // chamfer: mean two-way distance (fit units)
  };

  // Loss and gradient at x. `regularise_offsets` adds stage 3's terms, `priors` stage 2's.
  StepResult evaluate(const std::vector<double>& x, std::vector<double>& grad, std::uint32_t step, bool priors,
                      bool regularise_offsets) const {
    const PoseTrace t = pose_forward(model_, layout_, x);
    const std::size_t V = layout_.vertices;
    std::vector<float> body(3 * V);
    for (std::size_t i = 0; i < V; ++i)
      for (int c = 0; c < 3; ++c) body[3 * i + std::size_t(c)] = float(t.world[i][c]);
    const geometry::SurfaceSamples s = geometry::sample_surface(target_.mesh, o_.samples, o_.seed * 7919u + step);
    const std::size_t N = s.points.size() / 3;
    const geometry::PointIndex body_index(body), sample_index(s.points);
    std::vector<std::uint32_t> nearest_body(N), nearest_sample(V);
    parallel_for(N, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) nearest_body[k] = body_index.nearest(&s.points[3 * k]).first;
    });
    parallel_for(V, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) nearest_sample[k] = sample_index.nearest(&body[3 * k]).first;
    });
    std::vector<glm::dvec3> d_world(V, glm::dvec3(0.0));
    StepResult r;
    double dist_sum = 0;
    const double wc = o_.weights.chamfer;
    for (std::size_t k = 0; k < N; ++k) {
      const glm::dvec3 d = t.world[nearest_body[k]] - at(s.points, k);
      r.loss += wc * glm::dot(d, d) / double(N);
      d_world[nearest_body[k]] += wc * 2.0 * d / double(N);
      dist_sum += glm::length(d) / double(N);
    }
    for (std::size_t i = 0; i < V; ++i) {
      const glm::dvec3 d = t.world[i] - at(s.points, nearest_sample[i]);
      r.loss += wc * glm::dot(d, d) / double(V);
      d_world[i] += wc * 2.0 * d / double(V);
      dist_sum += glm::length(d) / double(V);
    }
    r.chamfer = dist_sum / 2.0;
    std::fill(grad.begin(), grad.end(), 0.0);
    if (regularise_offsets) r.loss += offset_regularisers(x, t, grad, d_world);
    pose_backward(model_, layout_, x, t, d_world, grad);
    if (priors) r.loss += pose_priors(x, grad);
    return r;
  }

  // Two-way chamfer of one part of the body: its vertices to the target, and the target points
  // whose nearest body vertex lies in the part back to the part. Both ways matter: an ear that
  // shrinks or tucks in sits close to the scan yet leaves the scan's ear uncovered.
  double part_chamfer(const std::vector<double>& x, const std::vector<bool>& in_part) const {
    const PoseTrace t = pose_forward(model_, layout_, x);
    std::vector<float> body(3 * layout_.vertices), part;
    std::vector<std::size_t> part_index;
    for (std::size_t i = 0; i < layout_.vertices; ++i) {
      for (int c = 0; c < 3; ++c) body[3 * i + std::size_t(c)] = float(t.world[i][c]);
      if (in_part[i]) part.insert(part.end(), {body[3 * i], body[3 * i + 1], body[3 * i + 2]}), part_index.push_back(i);
    }
    if (part_index.empty()) return 0.0;
    const geometry::SurfaceSamples s = geometry::sample_surface(target_.mesh, std::max<std::uint32_t>(o_.samples, 20000), o_.seed);
    const geometry::PointIndex samples(s.points), body_index(body), part_only(part);
    double out = 0, back = 0;
    for (std::size_t k = 0; k < part_index.size(); ++k) out += std::sqrt(double(samples.nearest(&part[3 * k]).second));
    std::size_t covered = 0;
    for (std::size_t k = 0; k < s.points.size() / 3; ++k) {
      if (!in_part[body_index.nearest(&s.points[3 * k]).first]) continue;
      back += std::sqrt(double(part_only.nearest(&s.points[3 * k]).second)), ++covered;
    }
    return out / double(part_index.size()) + (covered ? back / double(covered) : 0.0);
  }

  const PoseLayout& layout() const { return layout_; }

 private:
  double pose_priors(const std::vector<double>& x, std::vector<double>& grad) const {
    const BodyFitWeights& w = o_.weights;
    double loss = 0;
    for (std::size_t k = 1; k < layout_.joints; ++k) {  // the root's rotation is the global one
      const std::size_t i = layout_.joint_begin() + 3 * k;
      const glm::dvec3 a(x[i], x[i + 1], x[i + 2]);
      const double angle = glm::length(a);
      if (!free_[k]) {  // not on the ears or the tail's root: a hanging ear or tail is no unusual pose
        loss += w.pose_prior * angle * angle;
        for (int c = 0; c < 3; ++c) grad[i + std::size_t(c)] += 2.0 * w.pose_prior * a[c];
      }
      if (angle > limits_[k]) {
        const double excess = angle - limits_[k];
        loss += w.joint_limit * excess * excess;
        for (int c = 0; c < 3; ++c) grad[i + std::size_t(c)] += 2.0 * w.joint_limit * excess * a[c] / angle;
      }
    }
    for (std::size_t s = 0; s < layout_.shapes; ++s) {
      const double b = x[layout_.shape_begin() + s];
      loss += w.shape_prior * b * b;
      grad[layout_.shape_begin() + s] += 2.0 * w.shape_prior * b;
    }
    return loss;
  }

  // Laplacian and edge terms on the offsets scaled to fit units by the current scale (held constant
  // in these terms), normal consistency on the posed surface (gradient into d_world).
  double offset_regularisers(const std::vector<double>& x, const PoseTrace& t, std::vector<double>& grad,
                             std::vector<glm::dvec3>& d_world) const {
    const std::size_t V = layout_.vertices, base = layout_.offset_begin();
    std::vector<glm::dvec3> d(V), d_grad(V, glm::dvec3(0.0));
    for (std::size_t i = 0; i < V; ++i) d[i] = t.scale * glm::dvec3(x[base + 3 * i], x[base + 3 * i + 1], x[base + 3 * i + 2]);
    double loss = displacement_smoothness(topology_, d, o_.weights.laplacian, o_.weights.edge, d_grad);
    for (std::size_t i = 0; i < V; ++i)
      for (int c = 0; c < 3; ++c) grad[base + 3 * i + std::size_t(c)] += t.scale * d_grad[i][c];
    loss += normal_consistency(topology_, model_.triangles, t.world, o_.weights.normal, d_world);
    return loss;
  }

  const BodyModel& model_;
  const Target& target_;
  const BodyFitOptions& o_;
  PoseLayout layout_;
  MeshTopology topology_;
  std::vector<double> limits_;  // per joint, radians
  std::vector<bool> free_;      // per joint: ears and the tail's root turn freely
  std::optional<std::pair<std::size_t, std::size_t>> torso_;  // the torso's length and girth in the variables, when bounded

  // The torso's log aspect above the bound's; none when the model or the options have no bound.
  std::optional<double> torso_excess(const std::vector<double>& x) const {
    if (!torso_) return std::nullopt;
    return std::log1p(x[torso_->first]) - std::log1p(x[torso_->second]) - std::log(o_.min_torso_aspect);
  }
};

enum Active : unsigned { kGlobal = 1, kShapePose = 2, kOffsets = 4 };

// One stage: `steps` Adam steps over the active variables, the rate decaying linearly to a tenth.
FitStageReport run_stage(const Fitter& fitter, std::vector<double>& x, const std::string& name, std::uint32_t steps,
                         unsigned active, const BodyFitOptions& o, std::uint32_t& step_counter) {
  const auto start = std::chrono::steady_clock::now();
  const PoseLayout& L = fitter.layout();
  std::vector<nn::ParamGroup> groups;
  const auto group = [&](std::size_t begin, std::size_t count, double lr) {
    groups.push_back({begin, count, float(lr), 0.f});
  };
  if (active & kGlobal) group(0, PoseLayout::kGlobal, o.global_lr);
  if (active & kShapePose) {
    group(L.shape_begin(), L.shapes, o.shape_lr);
    group(L.joint_begin() + 3, 3 * (L.joints - 1), o.pose_lr);  // not the root
  }
  if (active & kOffsets) group(L.offset_begin(), 3 * L.vertices, o.offset_lr);
  nn::AdamStateRef<double> state;
  nn::AdamConfig config;
  std::vector<double> grad(x.size());
  FitStageReport report;
  report.name = name;
  report.steps = steps;
  const bool priors = active & kShapePose, regularise = active & kOffsets;
  for (std::uint32_t k = 0; k < steps; ++k) {
    const Fitter::StepResult r = fitter.evaluate(x, grad, step_counter++, priors, regularise);
    if (k == 0) report.chamfer_start = r.chamfer;
    report.chamfer_end = r.chamfer, report.loss_end = r.loss;
    const double decay = 1.0 - 0.9 * double(k) / double(std::max<std::uint32_t>(1, steps));
    nn::adam_step_ref(x, grad, state, config, groups, decay);
    if (active & kShapePose) fitter.bound_torso(x);
  }
  {  // the chamfer after the last step (or of the start, for a stage of 0 steps)
    const Fitter::StepResult r = fitter.evaluate(x, grad, step_counter++, priors, regularise);
    if (steps == 0) report.chamfer_start = r.chamfer;
    report.chamfer_end = r.chamfer, report.loss_end = r.loss;
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

// The template's rest-pose centre and RMS radius (animal frame).
void template_extent(const BodyModel& model, glm::dvec3& centre, double& radius) {
  centre = glm::dvec3(0.0);
  const std::size_t V = model.vertex_count();
  for (std::size_t i = 0; i < V; ++i) centre += at(model.template_vertices, i);
  centre /= double(V);
  double r2 = 0;
  for (std::size_t i = 0; i < V; ++i) r2 += glm::dot(at(model.template_vertices, i) - centre, at(model.template_vertices, i) - centre);
  radius = std::sqrt(r2 / double(V));
}

BodyFit finish(const BodyModel& model, const Target& target, const PoseLayout& L, std::vector<double> x,
               std::vector<FitStageReport> stages, json hypotheses) {
  BodyFit fit;
  const PoseTrace t = pose_forward(model, L, x);
  fit.variables = std::move(x);
  fit.fit_to_world = target.fit_to_world;
  fit.fitted.triangles = model.triangles;
  fit.fitted.regions = model.regions;
  fit.fitted.positions.resize(3 * L.vertices);
  for (std::size_t i = 0; i < L.vertices; ++i) {
    const glm::dvec3 p = glm::dvec3(target.fit_to_world * glm::dvec4(t.world[i], 1.0));
    for (int c = 0; c < 3; ++c) fit.fitted.positions[3 * i + std::size_t(c)] = float(p[c]);
  }
  geometry::compute_vertex_normals(fit.fitted);
  glm::dmat4 placement(t.scale * t.rotation);
  placement[3] = glm::dvec4(t.translation, 1.0);
  fit.animal_to_world = target.fit_to_world * placement;
  fit.stages = std::move(stages);
  fit.hypotheses = std::move(hypotheses);
  const FitStageReport& last = fit.stages.back();
  fit.chamfer_mean = last.chamfer_end * target.radius;
  fit.relative_chamfer = last.chamfer_end;
  fit.low_confidence = fit.relative_chamfer > kLowConfidence;
  return fit;
}

}  // namespace

bool ear_joint(const std::string& name) {
  if (name.find("Ear") != std::string::npos) return true;  // a word of a camel-case name: LEar, EarTip
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  for (std::size_t at = n.find("ear"); at != std::string::npos; at = n.find("ear", at + 1))
    if (at == 0 || !std::isalpha(static_cast<unsigned char>(n[at - 1]))) return true;  // ear_left, l_ear, EAR; not rear, beard
  return false;
}

BodyFit fit_body(const BodyModel& model, const geometry::Mesh& world_target, const FrameHints& hints,
                 const BodyFitOptions& o, const std::string& source) {
  model.validate(model.name.empty() ? "body model" : model.name);
  const Target target = normalise_target(world_target, source);
  const Fitter fitter(model, target, o);
  const PoseLayout& L = fitter.layout();
  glm::dvec3 template_centre;
  double template_radius;
  template_extent(model, template_centre, template_radius);
  const double scale = 1.0 / template_radius;

  // Hypotheses: up (the cameras', or each principal axis both ways) x the long horizontal axis
  // both ways x the second horizontal axis both ways.
  const geometry::SurfaceSamples cloud = geometry::sample_surface(target.mesh, 20000, 11);
  std::vector<glm::dvec3> ups;
  if (hints.up) {
    ups.push_back(glm::normalize(*hints.up));
  } else {
    for (const glm::dvec3& a : principal_axes(cloud.points, glm::dvec3(0.0))) ups.push_back(a), ups.push_back(-a);
  }
  std::vector<std::vector<double>> starts;
  for (const glm::dvec3& up : ups) {
    const std::vector<glm::dvec3> axes = principal_axes(cloud.points, up);
    for (int k = 0; k < 2; ++k)
      for (double sign : {1.0, -1.0}) {
        const glm::dvec3 forward = sign * axes[std::size_t(k)], left = glm::normalize(glm::cross(up, forward));
        const glm::dmat3 r(left, glm::normalize(glm::cross(forward, left)), forward);  // columns: animal x, y, z
        std::vector<double> x(L.size(), 0.0);
        const glm::dvec3 aa = axis_angle(r), t = -scale * (r * template_centre);
        for (int c = 0; c < 3; ++c) x[std::size_t(c)] = aa[c], x[3 + std::size_t(c)] = t[c];
        x[6] = std::log(scale);
        starts.push_back(std::move(x));
      }
  }
  std::uint32_t step = 0;
  json hypotheses = json::array();
  std::vector<double> best;
  double best_chamfer = std::numeric_limits<double>::infinity();
  for (std::size_t h = 0; h < starts.size(); ++h) {
    std::vector<double> x = starts[h];
    const FitStageReport r = run_stage(fitter, x, "hypothesis", o.hypothesis_steps, kGlobal, o, step);
    const glm::dmat3 rot = rodrigues({x[0], x[1], x[2]});
    hypotheses.push_back({{"up", {rot[1].x, rot[1].y, rot[1].z}},
                          {"forward", {rot[2].x, rot[2].y, rot[2].z}},
                          {"chamfer", r.chamfer_end * target.radius}});
    if (r.chamfer_end < best_chamfer) best_chamfer = r.chamfer_end, best = x;
  }
  if (best.empty())
    throw InputError(source + ": no initial placement of the body gave a finite fit (a degenerate surface?)");
  std::vector<FitStageReport> stages;
  stages.push_back(run_stage(fitter, best, "global", o.global_steps, kGlobal, o, step));
  // Ears hang or stand: gradient steps do not fold an upright ear down the side of the head, so
  // each droop is tried briefly before stage 2, as the placements were.
  std::vector<std::pair<std::size_t, double>> ears;  // joint, side (+1 left)
  for (std::size_t k = 0; k < model.joint_count(); ++k) {
    const std::string& n = model.joint_names[k];
    const int parent = model.parents[k];
    const bool ear = ear_joint(n) && n.find("tip") == std::string::npos;
    const bool parent_ear = parent >= 0 && ear_joint(model.joint_names[std::size_t(parent)]);
    if (ear && !parent_ear) ears.push_back({k, model.joint_template[3 * k] >= 0 ? 1.0 : -1.0});
  }
  if (!ears.empty()) {
    // Judged by the two-way chamfer of the head and ears (vertices skinned to the head joint or
    // below it): the whole body's chamfer barely notices a pair of ears (judged by it, three of the
    // twelve wide bench animals lost ear recall: 0.77 to 0.62, 0.82 to 0.52, 0.25 to 0.01).
    const std::vector<bool> head_vertices = vertices_below(model, model.parents[ears.front().first]);
    std::vector<double> best_ears;
    double best_ears_chamfer = std::numeric_limits<double>::infinity();
    for (const double droop : {0.0, 1.2, 2.4}) {
      std::vector<double> x = best;
      for (const auto& [k, side] : ears) x[L.joint_begin() + 3 * k + 2] = -side * droop;  // out and down about z
      const FitStageReport r = run_stage(fitter, x, "ears", o.hypothesis_steps, kGlobal | kShapePose, o, step);
      const double d = fitter.part_chamfer(x, head_vertices);
      hypotheses.push_back({{"ear_droop", droop}, {"head_chamfer", d * target.radius}, {"chamfer", r.chamfer_end * target.radius}});
      if (d < best_ears_chamfer) best_ears_chamfer = d, best_ears = x;
    }
    if (!best_ears.empty()) best = best_ears;
  }
  // A tail hangs, streams or stands: one hanging down along the hind legs lies in their fur
  // envelope, and from the template's the steps shrink it to a stub at the rump rather than swing
  // it down, so that the legs' labels take it. Each pitch of its root is tried briefly (both signs:
  // a SMAL model's axes are not the family's), judged by the whole body's chamfer: the tail's own
  // (as the ears are judged) favours the stub, whose few vertices sit close to the rump, where the
  // whole body's sees the hanging tail's fur explained (5 % lower on a tiger whose tail hangs
  // behind a hind leg to the ground; tail recall 0.05 to 0.74). The tail's chamfer is recorded.
  if (const int tail = tail_root(model); tail >= 0) {
    const std::vector<bool> tail_vertices = vertices_below(model, tail);
    std::vector<double> best_tail;
    double best_chamfer_so_far = std::numeric_limits<double>::infinity();
    for (const double pitch : {0.0, -0.75, -1.5, 0.75, 1.5}) {
      std::vector<double> x = best;
      x[L.joint_begin() + 3 * std::size_t(tail)] += pitch;  // about the animal's left-right axis
      const FitStageReport r = run_stage(fitter, x, "tail", o.hypothesis_steps, kGlobal | kShapePose, o, step);
      const double d = fitter.part_chamfer(x, tail_vertices);
      hypotheses.push_back({{"tail_pitch", pitch}, {"tail_chamfer", d * target.radius}, {"chamfer", r.chamfer_end * target.radius}});
      if (r.chamfer_end < best_chamfer_so_far) best_chamfer_so_far = r.chamfer_end, best_tail = x;
    }
    if (!best_tail.empty()) best = best_tail;
  }
  stages.push_back(run_stage(fitter, best, "shape_pose", o.pose_steps, kGlobal | kShapePose, o, step));
  stages.push_back(run_stage(fitter, best, "offsets", o.offset_steps, kGlobal | kShapePose | kOffsets, o, step));
  BodyFit fit = finish(model, target, L, std::move(best), std::move(stages), std::move(hypotheses));
  fit.torso_at_bound = fitter.torso_at_bound(fit.variables);
  for (FitStageReport& r : fit.stages) r.chamfer_start *= target.radius, r.chamfer_end *= target.radius;
  return fit;
}

BodyFit refit_body(const BodyModel& model, const geometry::Mesh& world_target, const BodyFit& start,
                   const BodyFitOptions& o, const std::string& source) {
  Target target = normalise_target(world_target, source);
  // Keep the first fit's frame: express the new target in it, so the variables carry over.
  const glm::dmat4 world_to_fit = glm::inverse(start.fit_to_world);
  for (std::size_t i = 0; i < target.mesh.vertex_count(); ++i) {
    const glm::dvec3 w = glm::dvec3(target.fit_to_world * glm::dvec4(at(target.mesh.positions, i), 1.0));
    const glm::dvec3 p = glm::dvec3(world_to_fit * glm::dvec4(w, 1.0));
    for (int c = 0; c < 3; ++c) target.mesh.positions[3 * i + std::size_t(c)] = float(p[c]);
  }
  target.fit_to_world = start.fit_to_world;
  target.radius = start.fit_to_world[0][0];
  const Fitter fitter(model, target, o);
  std::vector<double> x = start.variables;
  std::uint32_t step = 1u << 20;  // other samples than the first fit's
  std::vector<FitStageReport> stages;
  stages.push_back(run_stage(fitter, x, "shape_pose", o.pose_steps / 2, kGlobal | kShapePose, o, step));
  stages.push_back(run_stage(fitter, x, "offsets", o.offset_steps, kGlobal | kShapePose | kOffsets, o, step));
  BodyFit fit = finish(model, target, fitter.layout(), std::move(x), std::move(stages), json::array());
  fit.torso_at_bound = fitter.torso_at_bound(fit.variables);
  for (FitStageReport& r : fit.stages) r.chamfer_start *= target.radius, r.chamfer_end *= target.radius;
  return fit;
}

std::vector<glm::dvec3> fitted_joints(const BodyModel& model, const BodyFit& fit) {
  const PoseLayout layout = PoseLayout::of(model, fit.variables.size() == PoseLayout::of(model, true).size());
  if (fit.variables.size() != layout.size())
    throw InputError("body fit: " + std::to_string(fit.variables.size()) + " variables, the model needs " + std::to_string(layout.size()));
  const PoseTrace t = pose_forward(model, layout, fit.variables);
  std::vector<glm::dvec3> out(model.joint_count());
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = glm::dvec3(fit.fit_to_world * glm::dvec4(t.scale * (t.rotation * glm::dvec3(t.global[k][3])) + t.translation, 1.0));
  return out;
}

FittedEyes fitted_eyes(const BodyModel& model, const BodyFit& fit) {
  // The region detail's eye where the model has one, as the truth of a synth scene is measured
  // (the mean of a fine build's eye); the side is taken in the rest pose, +x the animal's left.
  const geometry::Mesh rest = region_carrier(model, rest_mesh(model)), posed = region_carrier(model, fit.fitted);
  glm::dvec3 sum[2]{glm::dvec3(0.0), glm::dvec3(0.0)};
  int count[2]{0, 0};
  for (std::size_t i = 0; i < rest.regions.size(); ++i) {
    if (rest.regions[i] != region_id(Region::eyes)) continue;
    const int side = rest.positions[3 * i] >= 0 ? 0 : 1;
    sum[side] += at(posed.positions, i), ++count[side];
  }
  if (count[0] == 0 || count[1] == 0)
    throw InputError((model.name.empty() ? std::string("body model") : model.name) + ": no eye-region vertices on the " +
                     (count[0] == 0 ? "left" : "right") + " side");
  return {sum[0] / double(count[0]), sum[1] / double(count[1])};
}

namespace {

BodyModel build_default_template() {
  const std::vector<std::string>& animals = known_animals();
  QuadrupedProportions mean = animal_proportions(animals.front());
  std::vector<QuadrupedProportions> all;
  for (const std::string& a : animals) all.push_back(animal_proportions(a));
  const auto average = [&](float QuadrupedProportions::*field) {
    double s = 0;
    for (const auto& p : all) s += p.*field;
    mean.*field = float(s / double(all.size()));
  };
  for (float QuadrupedProportions::*f :
       {&QuadrupedProportions::torso_length, &QuadrupedProportions::chest_radius, &QuadrupedProportions::waist_radius,
        &QuadrupedProportions::hip_radius, &QuadrupedProportions::torso_width_ratio, &QuadrupedProportions::front_leg_length,
        &QuadrupedProportions::rear_leg_length, &QuadrupedProportions::leg_radius_top, &QuadrupedProportions::leg_radius_bottom,
        &QuadrupedProportions::paw_radius, &QuadrupedProportions::neck_length, &QuadrupedProportions::neck_radius,
        &QuadrupedProportions::neck_pitch_deg, &QuadrupedProportions::head_radius, &QuadrupedProportions::muzzle_length,
        &QuadrupedProportions::muzzle_radius, &QuadrupedProportions::ear_length, &QuadrupedProportions::ear_width,
        &QuadrupedProportions::eye_radius, &QuadrupedProportions::tail_length, &QuadrupedProportions::tail_radius_base,
        &QuadrupedProportions::tail_radius_tip, &QuadrupedProportions::tail_pitch_deg, &QuadrupedProportions::tail_curl_deg})
    average(f);
  mean.animal = "quadruped";
  mean.ear_droop_deg = 0.0f;
  mean.mane = false;
  QuadrupedBuildOptions build;
  // About 7,000 vertices. Measured on posed procedural animals (default steps): 3,000 vertices
  // labelled 88 / 93 % of a dog / cat correctly in 10 s, 7,000 labelled 90 / 94 % in 12 s (small
  // parts gain most: eyes, paws, inner ears).
  build.voxel = mean.torso_length / 36.0f;
  BodyModel model = build_quadruped(mean, build);
  model.name = "quadruped (mean of " + std::to_string(all.size()) + " animals)";
  // Its regions from a build three times finer (63,630 vertices; both builds 0.4 s), carried on its
  // triangles: at 7,000 vertices an eye has 10, and labels moved from them by nearest vertex
  // covered a third of the true eye.
  QuadrupedBuildOptions fine_build;
  fine_build.voxel = build.voxel / 3.0f;
  fine_build.min_thickness = 2.5f * build.voxel;  // the template's ears, not thinner ones
  model.region_detail = attach_region_detail(model, rest_mesh(build_quadruped(mean, fine_build)));
  return model;
}

}  // namespace

BodyModel default_template() {
  // Built once a process (two marching-cubes builds, 0.4 s): the body and defur stages of one run each
  // ask for it, as do the tests.
  static const BodyModel model = build_default_template();
  return model;
}

}  // namespace nf::body
