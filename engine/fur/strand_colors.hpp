#pragma once
// A colour for every strand of the groom from the photos (issue: the groom looks like the animal):
// `controls` colours along each strand, at t = 1/C, 2/C .. 1 (the tip) of its points, linear RGB.
//
// A control point is seen by a view when it projects into the view's mask and lies no deeper than
// `hidden_depth` x its strand's length behind M_NeuS there (the fur in front of it hides the rest:
// roots under a thick coat are seen by no view, tips by most). Each seen control takes the view's
// photo colour at its projection (bilinear, in linear light), in two passes over the views:
//   1. the mean of its observations, a first estimate;
//   2. each view's exposure gain, the geometric mean of (first estimate / observation) over the
//      view's observations (a view into the sun, a flash, an automatic exposure), then the mean of
//      the observations times their view's gain, leaving out those whose luminance is more than
//      `outlier_ratio` off the first estimate (a highlight along the strand, a shadow).
// A strand that no view sees takes the mean colour of the `fill_neighbours` nearest seen strands
// (by root); a control that no view sees takes its strand's nearest seen control.
//
// Photos are read one at a time, so memory is the groom's controls and one photo, whatever the
// photos' count and size; the work is controls x views projections on the CPU, and a depth
// rasterisation of M_NeuS per view and pass on the device (kept for neither pass: a 50 MP depth map
// a view would not fit).
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/io/scene.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::fur {

struct StrandColorOptions {
  std::uint32_t controls = 3;
  double hidden_depth = 0.35;   // share of the strand's length
  double outlier_ratio = 2.0;   // > 1
  std::uint32_t fill_neighbours = 8;
};

struct StrandControls {
  std::uint32_t strands = 0, controls = 0;
  std::vector<float> points;   // strands x controls x 3, scene units
  std::vector<float> roots;    // strands x 3
  std::vector<float> lengths;  // per strand, scene units

  // The controls of strands of `points_per_strand` points each, from their contiguous xyz (appended:
  // a groom inferred in chunks is added chunk by chunk).
  void append(std::span<const float> xyz, std::uint32_t points_per_strand);
};

// The colour at `t` in [0, 1] from root to tip of a strand whose `controls` colours (linear RGB,
// `controls` x 3) sit at t = 1/C .. 1: interpolated between them, the first below it.
glm::vec3 control_color(const float* rgb, std::uint32_t controls, float t);

struct StrandColors {
  std::uint32_t controls = 0;
  std::vector<float> rgb;          // strands x controls x 3, linear RGB
  std::vector<std::uint8_t> seen;  // per strand: 1 when a view saw one of its controls
  json report;                     // views used, the share seen, the gains, seconds
  glm::vec3 at(std::uint64_t strand, float t) const { return control_color(&rgb[std::size_t(strand) * controls * 3], controls, t); }
};

// fur/colors.npz: `rgb` (strands x controls x 3, float32) and `seen` (per strand). The reader
// checks the shape against `strands` and every value (finite, not negative) and throws InputError
// naming the file and the array.
void write_strand_colors(const std::filesystem::path& file, const StrandColors& colors);
StrandColors read_strand_colors(const std::filesystem::path& file, std::uint64_t strands);

// `views`: the cameras to read (each with a photo and a mask). InputError naming the file when a
// photo or mask cannot be read or has another size than its camera.
StrandColors color_strands(gpu::Context& gpu, const io::Scene& scene, const std::vector<std::uint32_t>& views, const geometry::Mesh& envelope,
                           const StrandControls& strands, const StrandColorOptions& options);

// Several sets of controls (the groom's and the body's) in one pass over the photos: each photo is
// read, and M_NeuS's depth rasterised, twice in all rather than twice per set. Each set keeps its
// own options and its own exposure gains, so its colours equal color_strands' on it alone; every
// report's seconds are the shared pass's.
struct ControlSet {
  const StrandControls* controls = nullptr;
  StrandColorOptions options;
};
std::vector<StrandColors> color_control_sets(gpu::Context& gpu, const io::Scene& scene, const std::vector<std::uint32_t>& views,
                                             const geometry::Mesh& envelope, std::span<const ControlSet> sets);

}  // namespace nf::fur
