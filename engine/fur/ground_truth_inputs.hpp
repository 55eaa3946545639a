#pragma once
// The fur stage's inputs made from an `nf_gpu synth` scene's ground truth (gt/bald.ply with its
// regions, gt/knowledge.json turned into the world frame by gt/scene.json's animal_to_world,
// gt/outer.ply) instead of the earlier stages' outputs, through the same code those stages run
// (per-vertex knowledge, tangent field, roots, bald SDF, views). The learning test uses it, and the
// fur bench for baseline (b) (ground-truth body and roots) and to measure what each stage's error
// costs by swapping in the truth.
#include <filesystem>

#include "engine/defur/vertex_fur.hpp"
#include "engine/fur/fur_trainer.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::fur {

struct GroundTruthInputOptions {
  std::uint64_t roots = 100000;
  int hold_out_every = 5;
  FurViewOptions views;
  int sdf_resolution = 96;
  double smoothing_cm = 1.0;  // the tangent field's, as the frames stage
  // Turns every region's growth direction by this angle about the animal's up axis: a knowledge
  // that is wrong in a known way, for tests that the photos correct it.
  double heading_error_deg = 0;
  unsigned seed = 1;
  // Grow the true knowledge on this body (with its regions) instead of gt/bald.ply: the fur stage's
  // `truth=knowledge`, which measures what the knowledge's error costs on the pipeline's own M_bald.
  const geometry::Mesh* bald = nullptr;
  bool make_views = true;  // the training and held-out views (false: data.train/held_out stay empty)
};

struct GroundTruthInputs {
  geometry::Mesh bald, outer;
  defur::VertexFur vertex_fur;  // the true knowledge per vertex of `bald`
  FaceFrames frames;            // the tangent field of that knowledge on `bald`: more roots can be drawn
  FurTrainingData data;
};

// InputError naming the file when the scene has no ground truth or a file is missing or broken.
GroundTruthInputs ground_truth_inputs(gpu::Context& gpu, const std::filesystem::path& scene_dir, const GroundTruthInputOptions& options);

// The chamfer's queries, box and scale from M_NeuS (or the envelope standing in for it): points
// where fur grows (all of `outer` when it has no regions), the box grown by the longest fur, half
// its diagonal. Shared with the fur stage.
void set_surface_inputs(FurTrainingData& data, const geometry::Mesh& outer, const std::function<bool(std::int32_t)>& grows, unsigned seed);

}  // namespace nf::fur
