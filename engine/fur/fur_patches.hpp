#pragma once
// Native-resolution patches (issue: photos that pay). A photo of 12-50 MP shows strands that the
// stage's rendering grid (256-512 px) averages away, and a whole 4096 px view per step would make
// each step's cost grow with the photo. So each training step renders a window of one view at the
// photo's own resolution, `size` pixels square (the whole view when it is smaller), placed where
// the view has fur.
//
// The views' native targets (fur_views.hpp, NativeTargets: mask, fur, orientation weight, the
// multi-scale Gabor angle and its reliability) are computed once per view, written to a file of 4
// bytes a pixel in `dir` and dropped from memory; a patch reads its rows back (pread), and M_bald's
// depth is rasterised for the patch's camera. During training memory stays a patch's, whatever the
// photos' size and count (making one view's targets holds that photo's maps for a moment: a few
// GB for 50 MP). The files go when the store does, or (Files::kept: in the fur stage's resume
// folder) stay for a resumed run to reopen instead of making them anew from the photos.
//
// Placement: a patch is centred on a pixel drawn with probability proportional to the fur in its
// 16 x 16 tile (fur: mask and non-bald), then clamped into the view's crop, so every part of the
// fur is visited in proportion to its area. A function of (view, seed): resumed runs take the same
// patches.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "engine/fur/fur_views.hpp"

namespace nf::fur {

struct PatchPlace {
  std::uint32_t x0 = 0, y0 = 0, width = 0, height = 0;  // in the view's native crop
  bool operator==(const PatchPlace&) const = default;
};

class FurPatches {
 public:
  enum class Files { removed, kept };  // what becomes of the files when the store goes
  // `size` >= 16. `dir` is created; InputError naming it when it cannot be.
  FurPatches(gpu::Context& gpu, const geometry::Mesh& bald, std::filesystem::path dir, std::uint32_t size, Files files = Files::removed);
  ~FurPatches();  // removes the files it wrote, unless they are kept
  FurPatches(const FurPatches&) = delete;
  FurPatches& operator=(const FurPatches&) = delete;

  // Stores a view's targets (written to disk; `targets` may be dropped after). Returns its index.
  // InputError naming the file when it cannot be written (a full disk).
  // A camera is stored once (one file per camera in `dir`).
  std::uint32_t add(std::uint32_t camera, const NativeTargets& targets);
  // The camera's file an earlier store in `dir` kept, with the crop it was made for: its index, or
  // nullopt when there is no such file or it is not the crop's size (a run killed while writing it).
  std::optional<std::uint32_t> reopen(std::uint32_t camera, const io::Camera& crop);

  std::uint32_t size() const { return std::uint32_t(views_.size()); }
  std::uint32_t patch_size() const { return size_; }
  std::uint32_t camera(std::uint32_t view) const { return views_.at(view).camera; }
  const io::Camera& crop(std::uint32_t view) const { return views_.at(view).crop; }
  // The view's mean Gabor reliability over its oriented fur (the orientation loss's scale).
  double orientation_reliability(std::uint32_t view) const { return views_.at(view).reliability; }
  std::uint64_t fur_pixels(std::uint32_t view) const { return views_.at(view).tile_fur.empty() ? 0 : views_.at(view).tile_fur.back(); }
  std::uint64_t bytes_on_disk() const { return bytes_; }
  // Share of the oriented fur's pixels whose Gabor angle came from each scale (0: the photo's own).
  const std::vector<double>& scale_share() const { return scale_share_; }

  PatchPlace place(std::uint32_t view, std::uint64_t seed) const;
  // `count` places for scoring: `count` draws of place() from `seed`, repeats dropped (one when the
  // view fits in a patch).
  std::vector<PatchPlace> places(std::uint32_t view, std::uint32_t count, std::uint64_t seed) const;
  // The patch's targets as a FurView (crop: the patch's camera; rgb empty). InputError naming the
  // file when it cannot be read back.
  FurView cut(std::uint32_t view, const PatchPlace& place) const;

 private:
  struct Stored {
    std::uint32_t camera = 0;
    io::Camera crop;
    std::filesystem::path file;
    double reliability = 0, oriented = 0;
    std::uint32_t tiles_x = 0, tiles_y = 0;
    std::vector<std::uint64_t> tile_fur;  // cumulative fur pixels over the tiles (row-major)
    std::vector<std::uint64_t> scale_count;  // oriented pixels per Gabor scale
  };
  std::filesystem::path file_of(std::uint32_t camera) const;
  Stored start(std::uint32_t camera, const io::Camera& crop) const;
  static void account(Stored& s, const void* texels, std::uint32_t y);  // one stored row's fur, reliability and scales
  std::uint32_t finish(Stored&& s);
  gpu::Context& gpu_;
  const geometry::Mesh& bald_;
  std::filesystem::path dir_;
  std::uint32_t size_;
  Files files_;
  std::vector<Stored> views_;
  std::uint64_t bytes_ = 0;
  std::vector<double> scale_share_;
  std::vector<std::uint64_t> scale_count_;
};

}  // namespace nf::fur
