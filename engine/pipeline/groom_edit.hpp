#pragma once
// `nf_gpu edit`: a new export folder from a finished reconstruction without retraining: strands
// re-inferred from the trained fur field (fur/model.nfwt) on roots changed per region
// (export/region_edits.hpp). It writes into a folder of its own (never inside WORK) the export
// stage's files, the groom in scene units (SceneGroom) and edit.json, the edit as asked, so the
// result can be reproduced.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/gpu/context.hpp"
#include "engine/pipeline/export_files.hpp"

namespace nf::pipeline {

struct EditOptions {
  std::filesystem::path work, out;
  std::vector<std::string> sets;   // REGION.length_cm=X, REGION.hair_diameter_mm=X, REGION.density=X
  std::vector<std::string> shave;  // regions
  std::optional<std::uint32_t> strands;
  std::string quality = "draft";   // the previews' preset
  std::string formats;             // groom files (export.formats; empty: all)
  unsigned seed = 1;
};
json run_edit(gpu::Context& context, const EditOptions& options);


}  // namespace nf::pipeline
