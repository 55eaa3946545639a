#include "engine/fur/strand_colors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <mutex>

#include "engine/core/color.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/progress.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/defur/nonbald_masks.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/image.hpp"
#include "engine/io/npz.hpp"

namespace nf::fur {
namespace {

constexpr float kUnseenGrey = 0.18f;  // linear: a mid grey

// One view's photo (linear light), mask and M_NeuS depth, and its world-to-camera map.
struct ViewData {
  const io::Camera* camera = nullptr;
  glm::dmat4 world_to_camera{1.0};
  io::Image photo;
  std::vector<std::uint8_t> mask;
  std::vector<float> depth;
};

ViewData load_view(gpu::Context& gpu, const io::Camera& cam, const geometry::Mesh& envelope) {
  ViewData v;
  v.camera = &cam;
  v.world_to_camera = glm::inverse(cam.camera_to_world);
  v.photo = io::read_image(cam.image);
  if (v.photo.width != cam.width || v.photo.height != cam.height)
    throw InputError(cam.image.string() + ": not the size of camera '" + cam.name + "' (" + std::to_string(cam.width) + "x" +
                     std::to_string(cam.height) + ")");
  // PNG and JPEG photos are sRGB-encoded; an EXR holds linear light already.
  std::string extension = cam.image.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (extension != ".exr")
    for (float& p : v.photo.pixels) p = color::srgb_to_linear(std::clamp(p, 0.f, 1.f));
  v.mask = io::mask_of(io::read_image(cam.mask));
  if (v.mask.size() != std::size_t(cam.width) * cam.height) throw InputError(cam.mask.string() + ": not the size of camera '" + cam.name + "'");
  v.depth = defur::camera_depth(gpu, envelope, cam);
  return v;
}

// The photo's colour where the control point is seen, or false.
bool observe(const ViewData& v, const float* p, float length, double hidden_depth, glm::vec3& out) {
  const glm::dvec4 c = v.world_to_camera * glm::dvec4(p[0], p[1], p[2], 1.0);
  const double depth = -c.z;  // OpenGL: the camera looks down -z
  if (depth <= 0) return false;
  const io::Camera& cam = *v.camera;
  const double u = cam.cx + cam.fx * c.x / depth, w = cam.cy - cam.fy * c.y / depth;
  if (!(u >= 0.5 && w >= 0.5 && u < cam.width - 0.5 && w < cam.height - 0.5)) return false;
  const std::size_t pixel = std::size_t(w) * cam.width + std::size_t(u);
  if (!v.mask[pixel] || depth > double(v.depth[pixel]) + hidden_depth * length) return false;
  // Bilinear between the four pixel centres around (u, w).
  const double x = u - 0.5, y = w - 0.5;
  const std::uint32_t x0 = std::uint32_t(x), y0 = std::uint32_t(y);
  const float fx = float(x - x0), fy = float(y - y0);
  const io::Image& img = v.photo;
  const std::uint32_t ch = img.channels;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t c3 = ch >= 3 ? std::uint32_t(k) : 0;  // grey (+ alpha): the grey for every channel
    const float a = img.at(x0, y0, c3), b = img.at(x0 + 1, y0, c3), d = img.at(x0, y0 + 1, c3), e = img.at(x0 + 1, y0 + 1, c3);
    out[k] = (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * d + fx * e);
  }
  return true;
}

}  // namespace

void StrandControls::append(std::span<const float> xyz, std::uint32_t points_per_strand) {
  NF_CHECK(controls > 0 && points_per_strand > 1 && xyz.size() % (3 * std::size_t(points_per_strand)) == 0,
           "strand colours: controls of whole strands");
  const std::size_t count = xyz.size() / (3 * std::size_t(points_per_strand));
  for (std::size_t s = 0; s < count; ++s) {
    const float* strand = xyz.data() + 3 * s * points_per_strand;
    for (std::uint32_t c = 1; c <= controls; ++c) {
      const std::size_t k = std::size_t(std::lround(double(c) / controls * (points_per_strand - 1)));
      points.insert(points.end(), strand + 3 * k, strand + 3 * k + 3);
    }
    roots.insert(roots.end(), strand, strand + 3);
    float length = 0;
    for (std::uint32_t k = 1; k < points_per_strand; ++k)
      length += glm::distance(glm::vec3(strand[3 * k - 3], strand[3 * k - 2], strand[3 * k - 1]), glm::vec3(strand[3 * k], strand[3 * k + 1], strand[3 * k + 2]));
    lengths.push_back(length);
  }
  strands += std::uint32_t(count);
}

glm::vec3 control_color(const float* rgb, std::uint32_t controls, float t) {
  // Control c sits at t = (c + 1) / C; below the first the colour is the first's.
  const float x = std::clamp(t, 0.f, 1.f) * float(controls) - 1.f;
  const std::uint32_t c0 = std::uint32_t(std::clamp(std::floor(x), 0.f, float(controls - 1))), c1 = std::min(c0 + 1, controls - 1);
  const float f = std::clamp(x - float(c0), 0.f, 1.f);
  const float* a = rgb + 3 * c0;
  const float* b = rgb + 3 * c1;
  return {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

void write_strand_colors(const std::filesystem::path& file, const StrandColors& c) {
  const std::uint64_t n = c.seen.size();
  NF_CHECK(c.rgb.size() == n * c.controls * 3, "strand colours: arrays of another size than the strands");
  io::write_npz(file, {io::NpyWrite{"rgb", {n, c.controls, 3}, "<f4", {c.rgb.begin(), c.rgb.end()}},
                       io::NpyWrite{"seen", {n}, "<i4", {c.seen.begin(), c.seen.end()}}});
}

StrandColors read_strand_colors(const std::filesystem::path& file, std::uint64_t strands) {
  const io::NpyArray rgb = io::read_npz_array(file, "rgb");
  const io::NpyArray seen = io::read_npz_array(file, "seen");
  if (rgb.shape.size() != 3 || rgb.shape[0] != strands || rgb.shape[1] == 0 || rgb.shape[1] > 64 || rgb.shape[2] != 3)
    throw InputError(file.string() + ": 'rgb' should be " + std::to_string(strands) + " x controls (1-64) x 3, one row per strand; rerun the fur stage");
  if (seen.shape.size() != 1 || seen.shape[0] != strands)
    throw InputError(file.string() + ": 'seen' should hold " + std::to_string(strands) + " values, one per strand; rerun the fur stage");
  StrandColors c;
  c.controls = std::uint32_t(rgb.shape[1]);
  c.rgb.reserve(rgb.values.size());
  for (double v : rgb.values) {
    if (!std::isfinite(v) || v < 0 || v > 1e6) throw InputError(file.string() + ": 'rgb' holds " + std::to_string(v) + "; rerun the fur stage");
    c.rgb.push_back(float(v));
  }
  for (double v : seen.values) c.seen.push_back(v != 0 ? 1 : 0);
  return c;
}

namespace {

// One set of controls being coloured: its sums over the views in both passes (header comment).
class ColorSums {
 public:
  ColorSums(const StrandControls& in, const StrandColorOptions& o) : in_(in), o_(o), n_(std::size_t(in.strands) * in.controls) {
    NF_CHECK(o.controls == in.controls && o.outlier_ratio > 1 && in.points.size() == n_ * 3, "strand colours: controls and options disagree");
    first_.assign(n_, glm::vec3(0)), second_.assign(n_, glm::vec3(0));
    first_count_.assign(n_, 0.f), second_count_.assign(n_, 0.f);
  }

  // Pass 1: the plain mean of each control's observations. Each control is written by the one
  // thread that owns its strand.
  void add_first(const ViewData& v) {
    each_seen(v, [&](std::size_t i, glm::vec3 colour) { first_[i] += colour, first_count_[i] += 1; });
  }
  void end_first() {
    for (std::size_t i = 0; i < n_; ++i)
      if (first_count_[i] > 0) first_[i] /= first_count_[i];
  }

  // Pass 2: the view's gain, then the mean of the gained observations near the first estimate.
  void add_second(const ViewData& v) {
    // Each chunk's sums, added in the chunks' order: the same gain (and colours.npz) every run.
    std::vector<std::array<double, 3>> chunks;  // begin, sum, count
    std::mutex merge;
    parallel_for(in_.strands, [&](std::size_t begin, std::size_t end) {
      double local_sum = 0, local_count = 0;
      glm::vec3 colour;
      for (std::size_t i = begin * in_.controls; i < end * in_.controls; ++i) {
        if (!observe(v, &in_.points[3 * i], in_.lengths[i / in_.controls], o_.hidden_depth, colour)) continue;
        const float seen = color::luminance(colour), expected = color::luminance(first_[i]);
        if (seen <= 1e-4f || expected <= 1e-4f) continue;
        local_sum += std::clamp(std::log(double(expected) / seen), -1.0, 1.0), local_count += 1;  // a highlight is not an exposure
      }
      const std::lock_guard<std::mutex> lock(merge);
      chunks.push_back({double(begin), local_sum, local_count});
    });
    std::sort(chunks.begin(), chunks.end());
    double log_sum = 0, count = 0;
    for (const auto& [begin, sum, n_seen] : chunks) log_sum += sum, count += n_seen;
    const double gain = count > 0 ? std::exp(log_sum / count) : 1.0;
    gains_.push_back(gain);
    each_seen(v, [&](std::size_t i, glm::vec3 colour) {
      const glm::vec3 gained = colour * float(gain);
      const float seen = color::luminance(gained), expected = color::luminance(first_[i]);
      if (seen > expected * o_.outlier_ratio || seen * o_.outlier_ratio < expected) return;
      second_[i] += gained, second_count_[i] += 1;
    });
  }

  // The colours: seen controls, then a seen strand's unseen controls, then unseen strands.
  StrandColors finish(std::size_t views) const;

 private:
  void each_seen(const ViewData& v, const std::function<void(std::size_t control, glm::vec3 colour)>& body) const {
    parallel_for(in_.strands, [&](std::size_t begin, std::size_t end) {
      glm::vec3 colour;
      for (std::size_t s = begin; s < end; ++s)
        for (std::uint32_t c = 0; c < in_.controls; ++c) {
          const std::size_t i = s * in_.controls + c;
          if (observe(v, &in_.points[3 * i], in_.lengths[s], o_.hidden_depth, colour)) body(i, colour);
        }
    });
  }

  const StrandControls& in_;
  const StrandColorOptions o_;
  const std::size_t n_;
  std::vector<glm::vec3> first_, second_;
  std::vector<float> first_count_, second_count_;
  std::vector<double> gains_;
};

StrandColors ColorSums::finish(std::size_t views) const {
  const StrandControls& in = in_;
  const std::size_t n = n_;
  StrandColors out;
  out.controls = in.controls;
  // Seen controls: the second pass's mean (the first's when every observation was an outlier).
  out.rgb.assign(3 * n, 0.f);
  out.seen.assign(in.strands, 0);
  std::vector<std::uint8_t> control_seen(n, 0);
  std::uint64_t seen_controls = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (first_count_[i] == 0) continue;
    const glm::vec3 c = second_count_[i] > 0 ? second_[i] / second_count_[i] : first_[i];
    out.rgb[3 * i] = c.r, out.rgb[3 * i + 1] = c.g, out.rgb[3 * i + 2] = c.b;
    control_seen[i] = 1, out.seen[i / in.controls] = 1, ++seen_controls;
  }
  // A seen strand's unseen controls: its nearest seen control.
  for (std::size_t s = 0; s < in.strands; ++s) {
    if (!out.seen[s]) continue;
    for (std::uint32_t c = 0; c < in.controls; ++c) {
      if (control_seen[s * in.controls + c]) continue;
      for (std::uint32_t d = 1; d < in.controls; ++d) {
        const std::int64_t near = c + d < in.controls && control_seen[s * in.controls + c + d] ? std::int64_t(c + d)
                                  : c >= d && control_seen[s * in.controls + c - d]         ? std::int64_t(c - d)
                                                                                             : -1;
        if (near < 0) continue;
        std::copy_n(&out.rgb[3 * (s * in.controls + std::size_t(near))], 3, &out.rgb[3 * (s * in.controls + c)]);
        break;
      }
    }
  }
  // Strands no view sees: the mean of the nearest seen strands (by root).
  std::vector<float> seen_roots;
  std::vector<std::uint32_t> seen_ids;
  for (std::uint32_t s = 0; s < in.strands; ++s)
    if (out.seen[s]) seen_roots.insert(seen_roots.end(), &in.roots[3 * s], &in.roots[3 * s] + 3), seen_ids.push_back(s);
  const std::uint64_t unseen = in.strands - seen_ids.size();
  if (!seen_ids.empty() && unseen > 0) {
    const geometry::PointIndex index(seen_roots);
    parallel_for(in.strands, [&](std::size_t begin, std::size_t end) {
      for (std::size_t s = begin; s < end; ++s) {
        if (out.seen[s]) continue;
        const std::vector<std::uint32_t> near = index.nearest_k(&in.roots[3 * s], o_.fill_neighbours);
        for (std::uint32_t c = 0; c < in.controls; ++c) {
          glm::vec3 sum(0);
          for (std::uint32_t k : near) {
            const float* q = &out.rgb[3 * (std::size_t(seen_ids[k]) * in.controls + c)];
            sum += glm::vec3(q[0], q[1], q[2]);
          }
          sum /= float(near.size());
          float* p = &out.rgb[3 * (s * in.controls + c)];
          p[0] = sum.r, p[1] = sum.g, p[2] = sum.b;
        }
      }
    });
  }
  const double lo = gains_.empty() ? 1.0 : *std::min_element(gains_.begin(), gains_.end());
  const double hi = gains_.empty() ? 1.0 : *std::max_element(gains_.begin(), gains_.end());
  out.report = {{"views", views},
                {"controls", in.controls},
                {"strands_seen", double(seen_ids.size()) / std::max<double>(1, in.strands)},
                {"controls_seen", double(seen_controls) / std::max<double>(1, double(n))},
                {"view_gain_min", lo},
                {"view_gain_max", hi}};
  if (seen_ids.empty() && in.strands > 0) {
    // Nothing to copy from: a neutral grey, said in the report.
    std::fill(out.rgb.begin(), out.rgb.end(), kUnseenGrey);
    out.report["warning"] = "no view sees the fur; every strand is grey";
  }
  return out;
}

}  // namespace

std::vector<StrandColors> color_control_sets(gpu::Context& gpu, const io::Scene& scene, const std::vector<std::uint32_t>& views,
                                             const geometry::Mesh& envelope, std::span<const ControlSet> sets) {
  const Stopwatch clock;
  std::vector<ColorSums> sums;
  sums.reserve(sets.size());
  for (const ControlSet& set : sets) sums.emplace_back(*set.controls, set.options);
  // Each photo is read, and M_NeuS's depth rasterised, once a pass for every set.
  Progress progress("strand colours", 2 * views.size());
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1)
      for (ColorSums& s : sums) s.end_first();
    for (std::size_t vi = 0; vi < views.size(); ++vi) {
      const ViewData v = load_view(gpu, scene.cameras.at(views[vi]), envelope);
      for (ColorSums& s : sums) pass == 0 ? s.add_first(v) : s.add_second(v);
      progress.update(pass * views.size() + vi + 1);
    }
  }
  progress.finish();
  std::vector<StrandColors> out;
  for (const ColorSums& s : sums) out.push_back(s.finish(views.size()));
  const double seconds = clock.seconds();  // the pass all the sets shared
  for (StrandColors& c : out) c.report["seconds"] = seconds;
  return out;
}

StrandColors color_strands(gpu::Context& gpu, const io::Scene& scene, const std::vector<std::uint32_t>& views, const geometry::Mesh& envelope,
                           const StrandControls& strands, const StrandColorOptions& options) {
  const ControlSet set{&strands, options};
  return std::move(color_control_sets(gpu, scene, views, envelope, std::span<const ControlSet>(&set, 1)).front());
}

}  // namespace nf::fur
