#include "engine/bench/body_suite.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "engine/bench/record.hpp"
#include "engine/core/log.hpp"
#include "engine/pipeline/body_stage.hpp"
#include "engine/pipeline/stages.hpp"
#include "engine/synth/synth_scene.hpp"

namespace nf::bench {
namespace fs = std::filesystem;

json run_body_suite(gpu::Context& ctx, const Options& options) {
  const fs::path root = fs::temp_directory_path() / ("nf-bench-body-" + std::to_string(::getpid()));
  struct Cleanup {
    fs::path path;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } cleanup{root};
  const std::vector<std::string> animals = options.quick ? std::vector<std::string>{"cat"}
                                                         : std::vector<std::string>{"cat", "dog", "lion"};
  const std::vector<unsigned> seeds = options.quick ? std::vector<unsigned>{1} : std::vector<unsigned>{1, 2};
  const std::uint32_t neus_steps = options.quick ? 120 : 400;
  json records = json::array();
  for (const std::string& animal : animals)
    for (const unsigned seed : seeds) {
      const fs::path scene = root / (animal + std::to_string(seed)), work = root / (animal + std::to_string(seed) + "-work");
      synth::SynthOptions so;
      so.animal = animal, so.seed = seed;
      so.views = options.quick ? 12 : 24;
      so.resolution = options.quick ? 128 : 256;
      so.strands = options.quick ? 15000 : 60000;
      synth::synthesize_scene(scene, so);
      pipeline::ReconstructOptions ro;
      ro.scene = scene, ro.work = work, ro.quality = "draft";
      ro.run.to = "body";
      ro.settings = {"neus.steps=" + std::to_string(neus_steps)};
      log::info("bench body: ", animal, " seed ", seed, ": NeuS (", neus_steps, " steps), then the body stage");
      const auto outcomes = pipeline::reconstruct(ctx, ro);
      std::ifstream in(pipeline::body_outputs(work).metrics());
      const json m = json::parse(in);
      Timing timing;
      timing.seconds = {m.at("seconds").get<double>()};
      json metrics{{"stages", m.at("stages")},
                   {"relative_chamfer", m.at("relative_chamfer")},
                   {"chamfer_mean_scene_units", m.at("chamfer_mean")},
                   {"low_confidence", m.at("low_confidence")},
                   {"neus_seconds", outcomes.front().seconds}};
      if (m.contains("ground_truth")) {
        const json& gt = m["ground_truth"];
        metrics["label_accuracy"] = gt.at("accuracy");
        metrics["recall"] = gt.at("recall");
        if (gt.contains("eye_error_mm")) metrics["eye_error_mm"] = gt["eye_error_mm"];
      }
      const json params{{"animal", animal}, {"seed", seed}, {"views", so.views}, {"resolution", so.resolution},
                        {"neus_steps", neus_steps}, {"quality", "draft"}};
      records.push_back(make_record(ctx, "body", animal + "_seed" + std::to_string(seed), params, timing, metrics));
    }
  return records;
}

}  // namespace nf::bench
