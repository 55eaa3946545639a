#pragma once
// `nf_gpu synth`: a procedural furry quadruped with ground truth, rendered from two camera rings.
// Writes, into a new folder (atomically: a temp folder renamed at the end):
//   transforms.json, images/NNN.png, masks/NNN.png (body + fur coverage >= 1/2),
//   gt/strands.hair (scene units = metres), gt/bald.ply (region per vertex), gt/outer.ply (the fur
//   envelope, see fur_envelope.hpp), gt/knowledge.json (the preset it grew from, with the true eye
//   distance and each region's effective thickness, see effective_thickness.hpp), gt/scene.json (cm per unit, eye centres,
//   body parameters, how outer.ply was made, timings), gt/body.glb (the bald body, for viewing), and
//   with true_orientation gt/orientation/NNN.exr.
#include <cstdint>
#include <filesystem>
#include <string>

#include "engine/body/quadruped.hpp"
#include "engine/core/json.hpp"

namespace nf::synth {

struct SynthOptions {
  std::string animal = "cat";
  std::uint32_t views = 36, resolution = 512;
  unsigned seed = 1;
  std::uint32_t strands = 100000;
  std::uint32_t points_per_strand = 100;
  std::uint32_t samples_per_axis = 3;  // anti-aliasing: s x s samples per pixel
  float body_voxel = 0;                // metres; 0: the body model's default
  // How far an animal may stray from its family, to judge the later stages on bodies and coats
  // wider than the presets: every body proportion scaled by a seeded factor in [1 - s, 1 + s]
  // (and the neck's and tail's pitch, body::vary_proportions), and each region's fur length by one in
  // [1 - f, 1 + f]. gt/knowledge.json holds the lengths grown.
  float proportion_spread = body::kDefaultProportionSpread;
  float fur_length_spread = 0;
  // The world frame the files are written in (world_frame.hpp): "y-up-m" (y up, metres) or
  // "z-up-mm" (z up, millimetres, the animal metres from the origin). The animal, the photos and
  // the masks are the same in both; only the coordinates of everything else change.
  std::string frame = "y-up-m";
  // The photos' look, to make scenes unlike the defaults (a renderer the engine was not tuned on):
  // the strands' shading (strand_renderer.hpp: kajiya-kay, two-lobe, matte), their rendered width
  // as a multiple of the style's, and Gaussian sensor noise added to each photo's 8-bit values
  // (sigma in levels of 255, seeded by the scene's seed and the view).
  std::string shading = "kajiya-kay";
  float hair_width = 1;
  float photo_noise = 0;
  // What surrounds the animal (backdrop.hpp): "plain" (one flat colour) or "textured" (a patterned
  // floor and wall, for structure-from-motion and for masks no threshold can make).
  std::string backdrop = "plain";
  // "png" (lossless), or "jpeg": what cameras write (quality 92) with the EXIF a camera adds (maker,
  // model, focal length in mm and as the 35 mm equivalent of a 36 mm wide sensor), which COLMAP
  // takes its first focal length from.
  std::string photo_format = "png";
  // "rings" (a rig: two even rings) or "handheld" (a person walking round: camera_rig.hpp), and how
  // many views (spread evenly) are motion-blurred, a sideways shake of 1.5 % of the width.
  std::string camera_path = "rings";
  std::uint32_t blurred_views = 0;
  bool overwrite = false;              // replace an existing synth output folder
  // Also write gt/orientation/<camera>.exr: the true on-screen orientation of the strands each pixel
  // shows (strand_renderer.hpp), the reference `nf_gpu orient` judges Gabor maps against.
  bool true_orientation = false;
};

// Returns the gt/scene.json content. Refuses (UsageError) to write into an existing folder unless
// it is an earlier synth output and `overwrite` is set; user files are never replaced.
json synthesize_scene(const std::filesystem::path& out, const SynthOptions& options);

// The version of the truth synth writes (gt/scene.json "truth_version"): raised when a true value
// was wrong, so that a cached scene made before is made again. 2: each eye's centre from its own
// vertices (a turned head had mixed them).
inline constexpr int kTruthVersion = 2;
// Whether `scene` holds a synth scene whose truth is of kTruthVersion.
bool truth_is_current(const std::filesystem::path& scene);

}  // namespace nf::synth
