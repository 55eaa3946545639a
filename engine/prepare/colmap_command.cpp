#include "engine/prepare/colmap_command.hpp"

#include <cstdlib>

#include "engine/prepare/external_tool.hpp"

namespace nf::prepare {

std::string colmap_executable() {
  return find_tool("colmap", "NF_COLMAP",
                   "prepare needs COLMAP to find the cameras and none is on PATH: install it (Debian: apt-get install colmap), "
                   "set NF_COLMAP to its binary, or pass --colmap with a model COLMAP made elsewhere");
}

double run_colmap(const std::string& command, const std::vector<std::string>& args, const std::filesystem::path& log) {
  std::vector<std::string> words = {command};
  words.insert(words.end(), args.begin(), args.end());
  // COLMAP's binary links Qt even for its command-line steps, and there is no display to open; its
  // glog lines go to its stderr (the log), not to files in /tmp.
  setenv("QT_QPA_PLATFORM", "offscreen", 0);
  setenv("GLOG_logtostderr", "1", 0);
  return run_tool(colmap_executable(), "colmap " + command, words, log);
}

}  // namespace nf::prepare
