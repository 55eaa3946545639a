#pragma once
// What the fur stage's image losses compare against, per camera: the view at the stage's rendering
// resolution (the photo's longer side scaled to at most `max_side`), cropped to its mask's box
// grown by a margin (no work on pixels far from the animal), with the camera shifted and scaled to
// match. Targets per pixel of that crop, each the average over the photo pixels it covers:
//   mask                the animal's mask (soft at the border)
//   silhouette_weight   1 - mask (1 - nonbald): the silhouette loss sees fur and background, not
//                       the bald parts of the animal (eyes, nose, pads), where no strand should be
//   orientation_weight  mask x nonbald, eroded by `outline_px`: orientation is supervised on fur
//                       only, away from the outline
//   gabor_angle         the Gabor map of the full photo (engine/orient), averaged as doubled-angle
//                       vectors weighted by confidence: a coarse pixel keeps the dominant orientation
//   gabor_confidence    how far that orientation can be trusted, in [0, 1]: the coherence of the
//                       Gabor orientations in a window of at least coherence_px photo pixels,
//                       above the coherence as many random orientations would show (0). Gabor maps
//                       of textureless fur (sub-pixel strands, smooth shading) answer noise with
//                       confident but incoherent angles; this keeps them out of the loss
//   orientation_reliability  the view's mean gabor_confidence over its fur: the orientation loss
//                       of the view is scaled by it, so a photo without usable fur texture barely
//                       pulls (the loss itself is normalised by its own weights, scale-free)
//   body_depth          M_bald's depth (the rasteriser's occluder), +inf where no body
//   rgb                 the photo (previews)
#include <cstdint>
#include <vector>

#include "engine/geometry/mesh.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/orient/gabor_bank.hpp"
#include "engine/splat/rasterizer.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::fur {

struct FurViewOptions {
  std::uint32_t max_side = 512;  // 0: the photo's own resolution
  std::uint32_t margin_px = 8;   // at the rendering resolution
  // Photo pixels nearer the mask's border than this carry no orientation target: there the Gabor
  // filters answer the animal's outline against the background, not the fur (-1: the filters'
  // radius, support x max(sigma_x, sigma_y)).
  int outline_px = -1;
  std::uint32_t coherence_px = 9;  // photo pixels: the orientation reliability's window
  // Scales of the native-resolution targets' Gabor maps (orientation_scales.hpp): the photo and
  // its halvings (the stage sets it per view, gabor_scales_for). The targets at the rendering
  // resolution use the photo's own map only.
  std::uint32_t gabor_scales = 1;
  orient::GaborParams gabor;
  // The scene's true orientation map (gt/orientation/<camera>.exr, synth --true-orientation) in
  // place of the photo's Gabor map, with one scale: what a perfect map would buy.
  bool true_orientation = false;
};

struct FurView {
  std::uint32_t camera = 0;
  io::Camera crop;  // the cropped, scaled camera (width x height: the crop)
  std::vector<float> mask, silhouette_weight, orientation_weight, gabor_angle, gabor_confidence, body_depth;
  std::vector<float> rgb;  // the photo at the crop (3 per pixel), for previews
  double orientation_reliability = 0;
  double scale = 1;  // rendering pixels per photo pixel
  std::uint64_t pixels() const { return std::uint64_t(crop.width) * crop.height; }
};

// The view's targets at the photo's own resolution over the same box as the view's crop (the mask's
// box grown by margin_px rendering pixels): what native-resolution patches are cut from
// (fur_patches.hpp). At that resolution the mask, the fur and the orientation weight are binary.
struct NativeTargets {
  io::Camera crop;  // the camera cropped to the box, at scale 1
  enum Flag : std::uint8_t { kMask = 1, kFur = 2, kOriented = 4 };  // kFur: mask and non-bald; kOriented: fur away from the outline
  std::vector<std::uint8_t> flags;
  std::vector<float> angle, confidence;  // the best of the scales' Gabor orientations and its reliability
  std::vector<std::uint8_t> scale;        // which scale that was (0: the photo's own)
  std::uint64_t pixels() const { return std::uint64_t(crop.width) * crop.height; }
};

// `nonbald`: the defur stage's mask for this camera (full resolution), or empty for "all fur".
// InputError naming the file when the photo or mask cannot be read or the mask is empty.
FurView make_fur_view(gpu::Context& gpu, const io::Scene& scene, std::uint32_t camera, const io::Image* nonbald,
                      const geometry::Mesh& bald, const FurViewOptions& options, NativeTargets* native = nullptr);


}  // namespace nf::fur
