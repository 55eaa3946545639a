#pragma once
// The synthetic scenes' renderer: CPU ray tracing (Embree) of strands as round linear curves and of
// the body as triangles, Kajiya-Kay hair shading, stratified supersampling for anti-aliasing. It
// shares no code or maths with the engine's Gaussian strand splatting on purpose: images it makes
// are the independent ground truth the splatter is judged against.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/strands.hpp"
#include "engine/synth/backdrop.hpp"

namespace nf::synth {

// How strands reflect light. kajiya-kay: diffuse along the tangent and one white highlight (the
// default); two-lobe: Marschner's two highlights, a white one shifted towards the root (R) and a
// coloured one towards the tip (TRT), each a Gaussian in the longitudinal half angle; matte:
// diffuse only, no highlight (fur whose strands show no sheen).
enum class HairShading { KajiyaKay, TwoLobe, Matte };
HairShading hair_shading_from(const std::string& name);  // UsageError for an unknown name
const std::vector<std::string>& hair_shading_names();

struct RenderOptions {
  std::uint32_t samples_per_axis = 3;   // s x s stratified samples per pixel
  HairShading shading = HairShading::KajiyaKay;
  Backdrop backdrop;                    // what rays that miss the animal see
  std::uint32_t render_points = 34;     // points per strand traced (resampled from the strand's own)
  bool true_orientation = false;        // also return Rendered::orientation
};

// A strand's colour (linear RGB) at `along` in [0, 1] from root to tip, given its root colour: what
// the renderer shades and the scene's true strands carry (gt/strands.hair's colour array).
glm::vec3 strand_albedo(glm::vec3 base, float along);

struct StrandLook {
  std::vector<glm::vec3> root_colors;   // linear RGB per strand (empty: grey)
  float radius = 0.001f;                // scene units
};

struct BodyLook {
  std::vector<glm::vec3> vertex_colors; // linear RGB per vertex (empty: grey)
};

struct Rendered {
  io::Image rgb;       // sRGB-encoded, 3 channels
  io::Image coverage;  // fraction of samples that hit the animal, 1 channel
  // With RenderOptions::true_orientation, 2 channels: the on-screen orientation of the strands the
  // samples see first (radians in [0, pi), engine/orient's convention: what a perfect orientation
  // map of the photo would hold) and its weight, the length of the samples' mean doubled-angle
  // vector: 1 where every sample sees a strand and they agree, less at the body, the background,
  // crossings and the outline. The reference Gabor maps are judged against.
  io::Image orientation;
};

// The body may be empty (no triangles): then only the strands are traced.
class StrandRenderer {
 public:
  StrandRenderer(const geometry::Mesh& body, const BodyLook& body_look, const io::StrandSet& strands, const StrandLook& look,
                 const RenderOptions& options);
  ~StrandRenderer();
  StrandRenderer(const StrandRenderer&) = delete;
  StrandRenderer& operator=(const StrandRenderer&) = delete;

  Rendered render(const io::Camera& camera) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nf::synth
