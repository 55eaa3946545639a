#pragma once
// `nf_gpu pose`: the exported animal posed with its skeleton (WORK/export/body.glb): the body by
// linear blend skinning, each strand rigidly with its root's face (export/pose_groom.hpp). It
// writes the export stage's files into a folder of its own (never inside WORK) and pose.json, the
// rotations asked.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::pipeline {

struct PoseOptions {
  std::filesystem::path work, out;
  std::filesystem::path groom;    // an edit's folder to pose instead of WORK's groom (empty: WORK's)
  std::vector<std::string> sets;  // joint.NAME=rx,ry,rz (a rotation vector in degrees, export frame)
  std::string quality = "draft";
  std::string formats;  // groom files (export.formats; empty: all)
};
json run_pose(const PoseOptions& options);

}  // namespace nf::pipeline
