// Device and disk faults end in clear errors and lose nothing: a lost device (injected with
// NF_FAULT_DEVICE_LOST) is exit code 3 naming the stage and the pass that ran, and the rerun resumes
// from the checkpoint; a device too small for the settings (NF_FAULT_DEVICE_MEMORY_MB, and a real
// request larger than the machine) is exit code 3 naming the settings to lower; a disk that fills
// while a stage writes (a file-size limit) leaves the previous result byte-identical.
#include <doctest/doctest.h>

#include "tests/support/nf_process.hpp"

namespace fs = std::filesystem;
using namespace nf::test;

namespace {

const std::string kNeus =
    " --quality draft --set neus.steps=60 --set neus.checkpoint_interval=10 --set neus.rays=128 --set neus.samples_per_ray=16"
    " --set neus.fine_samples=8 --set neus.hull_fit_steps=5 --set neus.mesh_resolution=48 --set neus.hull_resolution=48 --to neus";

bool has(const Result& r, const std::string& text) { return r.output.find(text) != std::string::npos; }

// No half-written stage folder or temporary file anywhere under `work`.
void check_no_leftovers(const fs::path& work) {
  for (const auto& e : fs::recursive_directory_iterator(work)) {
    const std::string name = e.path().filename().string();
    CHECK_MESSAGE(name.find(".partial") == std::string::npos, e.path());
    CHECK_MESSAGE(name.find(".tmp") == std::string::npos, e.path());
  }
}

}  // namespace

TEST_CASE("device and disk faults end in clear errors and keep every earlier result") {
  const fs::path root = fs::temp_directory_path() / "nf_faults";
  fs::remove_all(root);
  const fs::path scene = root / "scene", work = root / "work";
  REQUIRE(run("synth --animal cat --views 8 --res 64 --strands 4000 --spp-axis 1 --out " + scene.string()).code == 0);
  const std::string args = "reconstruct --scene " + scene.string() + " --out " + work.string() + kNeus;

  SUBCASE("a lost device: exit 3 with the stage and the pass, then the rerun resumes") {
    const Result lost = run(args, "NF_FAULT_DEVICE_LOST=40");
    CHECK(lost.code == 3);
    CHECK_MESSAGE(has(lost, "stage neus: the GPU device was lost"), lost.output);
    CHECK_MESSAGE((has(lost, "pass '") || has(lost, "kernels ")), lost.output);
    CHECK_MESSAGE(has(lost, "rerun the same command to resume"), lost.output);
    CHECK(!fs::exists(work / "neus"));
    CHECK(fs::exists(work / ".resume" / "neus" / "checkpoint.nfwt"));
    check_no_leftovers(work);
    const Result resumed = run(args);
    CHECK_MESSAGE(resumed.code == 0, resumed.output);
    CHECK_MESSAGE(has(resumed, "neus: resuming from"), resumed.output);
    CHECK(fs::exists(work / "neus" / "outer.ply"));
  }

  SUBCASE("too little device memory: exit 3 naming the settings to lower") {
    const Result small = run(args, "NF_FAULT_DEVICE_MEMORY_MB=2");
    CHECK(small.code == 3);
    CHECK_MESSAGE(has(small, "stage neus: buffer '"), small.output);
    CHECK_MESSAGE(has(small, "out of memory"), small.output);
    CHECK_MESSAGE(has(small, "--set neus.rays (now 128)"), small.output);
    CHECK(!fs::exists(work / "neus"));
    check_no_leftovers(work);
    // Settings whose product no device holds are refused before any stage runs (usage, exit 2).
    const Result huge = run(args + " --set neus.rays=1048576 --set neus.samples_per_ray=1024");
    CHECK(huge.code == 2);
    CHECK_MESSAGE(has(huge, "rays x samples_per_ray"), huge.output);
    // A real request larger than the machine (a 2048^3 grid for the mesh, 34 GB of floats, under a
    // 16 GB address-space limit) is a clear error naming the setting, not a kill by the kernel.
    const Result grid = run(args + " --set neus.mesh_resolution=2048", "ulimit -v 16000000;");
    CHECK(grid.code == 3);
    CHECK_MESSAGE(has(grid, "stage neus: out of host memory"), grid.output);
    CHECK_MESSAGE(has(grid, "--set neus.mesh_resolution (now 2048)"), grid.output);
    CHECK(!fs::exists(work / "neus"));
  }

  SUBCASE("a disk that fills while writing leaves the previous result intact") {
    REQUIRE(run(args).code == 0);
    const auto before = snapshot(work / "neus");
    // 64 blocks per file: the checkpoint and the mesh cannot be written. nf_gpu ignores SIGXFSZ
    // itself, so the write fails with EFBIG, as on a full disk, instead of killing the process.
    const Result full = run(args + " --from neus", "ulimit -f 64;");
    CHECK(full.code == 1);
    CHECK_MESSAGE(has(full, "the file-size limit was reached"), full.output);
    CHECK_MESSAGE(has(full, "nothing was left in its place"), full.output);
    CHECK(snapshot(work / "neus") == before);
    check_no_leftovers(work);
  }
  fs::remove_all(root);
}
