#include "engine/fur/fur_patches.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <random>

#include "engine/core/error.hpp"
#include "engine/defur/nonbald_masks.hpp"

namespace nf::fur {
namespace {

constexpr std::uint32_t kTile = 16;
// A texel's flags byte: NativeTargets' flags in the low bits, the Gabor scale in the high four.
constexpr std::uint8_t kFlagBits = 0x0F, kMaxScale = 15;
constexpr int kScaleShift = 4;

// One pixel on disk: the flags, the reliability in 1/255 and the angle in pi/65536.
struct Texel {
  std::uint8_t flags, reliability;
  std::uint16_t angle;
};
static_assert(sizeof(Texel) == 4);

std::string system_error(const std::filesystem::path& file, const char* what) {
  return file.string() + ": " + what + " (" + std::strerror(errno) + ")";
}

}  // namespace

FurPatches::FurPatches(gpu::Context& gpu, const geometry::Mesh& bald, std::filesystem::path dir, std::uint32_t size, Files files)
    : gpu_(gpu), bald_(bald), dir_(std::move(dir)), size_(size), files_(files) {
  if (size < 16) throw InputError("fur patches: a patch must be at least 16 pixels (got " + std::to_string(size) + ")");
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw InputError(dir_.string() + ": cannot create the patch store's folder (" + ec.message() + ")");
}

FurPatches::~FurPatches() {
  if (files_ == Files::kept) return;
  std::error_code ec;
  for (const Stored& v : views_) std::filesystem::remove(v.file, ec);
  std::filesystem::remove(dir_, ec);  // only when empty: nothing else is touched
}

void FurPatches::account(Stored& s, const void* texels, std::uint32_t y) {
  const Texel* row = static_cast<const Texel*>(texels);
  for (std::uint32_t x = 0; x < s.crop.width; ++x) {
    const std::uint8_t f = row[x].flags;
    if (f & NativeTargets::kFur) ++s.tile_fur[std::size_t(y / kTile) * s.tiles_x + x / kTile];
    if (f & NativeTargets::kOriented) {
      s.reliability += row[x].reliability / 255.0, s.oriented += 1;
      const std::size_t scale = f >> kScaleShift;
      if (s.scale_count.size() <= scale) s.scale_count.resize(scale + 1, 0);
      ++s.scale_count[scale];
    }
  }
}

std::uint32_t FurPatches::finish(Stored&& s) {
  // (account() counted fur per tile and summed the reliability: now the cumulative counts and the mean.)
  s.reliability = s.oriented > 0 ? s.reliability / s.oriented : 0.0;
  std::uint64_t total = 0;
  for (std::uint64_t& k : s.tile_fur) k = total += k;
  bytes_ += std::uint64_t(s.crop.width) * s.crop.height * sizeof(Texel);
  // (The store's scale counts take a view's only once it is stored: a view that failed halfway adds none.)
  if (scale_count_.size() < s.scale_count.size()) scale_count_.resize(s.scale_count.size(), 0);
  for (std::size_t k = 0; k < s.scale_count.size(); ++k) scale_count_[k] += s.scale_count[k];
  views_.push_back(std::move(s));
  std::uint64_t all = 0;
  for (std::uint64_t c : scale_count_) all += c;
  scale_share_.assign(scale_count_.size(), 0.0);
  for (std::size_t k = 0; k < scale_count_.size(); ++k) scale_share_[k] = all ? double(scale_count_[k]) / double(all) : 0.0;
  return std::uint32_t(views_.size() - 1);
}

FurPatches::Stored FurPatches::start(std::uint32_t camera, const io::Camera& crop) const {
  for (const Stored& v : views_)
    NF_CHECK(v.camera != camera, "fur patches: camera " + std::to_string(camera) + " stored twice");
  Stored s;
  s.camera = camera, s.crop = crop;
  s.file = file_of(camera);
  s.tiles_x = (crop.width + kTile - 1) / kTile, s.tiles_y = (crop.height + kTile - 1) / kTile;
  s.tile_fur.assign(std::size_t(s.tiles_x) * s.tiles_y, 0);
  return s;
}

std::filesystem::path FurPatches::file_of(std::uint32_t camera) const {
  return dir_ / ("camera_" + std::to_string(camera) + ".nftargets");
}

std::uint32_t FurPatches::add(std::uint32_t camera, const NativeTargets& t) {
  Stored s = start(camera, t.crop);
  const std::uint32_t W = t.crop.width, H = t.crop.height;
  std::vector<Texel> row(W);
  const int fd = ::open(s.file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(system_error(s.file, "cannot write the view's native targets"));
  const auto fail = [&](const char* what) {
    const std::string message = system_error(s.file, what);
    ::close(fd);
    ::unlink(s.file.c_str());  // nothing half-written left behind
    return InputError(message);
  };
  for (std::uint32_t y = 0; y < H; ++y) {
    for (std::uint32_t x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      const float a = std::clamp(t.angle[i], 0.f, float(M_PI));
      row[x] = {std::uint8_t((t.flags[i] & kFlagBits) | (std::min<std::uint8_t>(t.scale[i], kMaxScale) << kScaleShift)),
                std::uint8_t(std::lround(std::clamp(t.confidence[i], 0.f, 1.f) * 255.f)),
                std::uint16_t(std::lround(a / M_PI * 65536.0) & 0xFFFF)};  // pi wraps to 0: angles are mod pi
    }
    account(s, row.data(), y);  // from the stored values: a reopened store counts the same
    const std::size_t bytes = std::size_t(W) * sizeof(Texel);
    if (::write(fd, row.data(), bytes) != ssize_t(bytes)) throw fail("cannot write the view's native targets (is the disk full?)");
  }
  if (::close(fd) != 0) {
    const std::string message = system_error(s.file, "cannot write the view's native targets");
    ::unlink(s.file.c_str());
    throw InputError(message);
  }
  return finish(std::move(s));
}

std::optional<std::uint32_t> FurPatches::reopen(std::uint32_t camera, const io::Camera& crop) {
  const std::filesystem::path file = file_of(camera);
  std::error_code ec;
  const std::uint64_t bytes = std::filesystem::file_size(file, ec);
  if (ec || bytes != std::uint64_t(crop.width) * crop.height * sizeof(Texel)) return std::nullopt;
  Stored s = start(camera, crop);
  std::vector<Texel> row(crop.width);
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  const std::size_t row_bytes = std::size_t(crop.width) * sizeof(Texel);
  for (std::uint32_t y = 0; y < crop.height; ++y) {
    if (::read(fd, row.data(), row_bytes) != ssize_t(row_bytes)) {
      ::close(fd);
      return std::nullopt;
    }
    account(s, row.data(), y);
  }
  ::close(fd);
  return finish(std::move(s));
}

PatchPlace FurPatches::place(std::uint32_t view, std::uint64_t seed) const {
  const Stored& s = views_.at(view);
  const std::uint32_t W = s.crop.width, H = s.crop.height;
  PatchPlace p{0, 0, std::min(W, size_), std::min(H, size_)};
  if (p.width == W && p.height == H) return p;
  std::mt19937_64 rng(seed);
  std::uint32_t cx = W / 2, cy = H / 2;
  const std::uint64_t total = s.tile_fur.empty() ? 0 : s.tile_fur.back();
  if (total > 0) {
    const std::uint64_t pick = std::uniform_int_distribution<std::uint64_t>(0, total - 1)(rng);
    const auto tile = std::size_t(std::upper_bound(s.tile_fur.begin(), s.tile_fur.end(), pick) - s.tile_fur.begin());
    const std::uint32_t tx = std::uint32_t(tile % s.tiles_x), ty = std::uint32_t(tile / s.tiles_x);
    cx = std::min(W - 1, tx * kTile + std::uniform_int_distribution<std::uint32_t>(0, kTile - 1)(rng));
    cy = std::min(H - 1, ty * kTile + std::uniform_int_distribution<std::uint32_t>(0, kTile - 1)(rng));
  }
  p.x0 = std::uint32_t(std::clamp<std::int64_t>(std::int64_t(cx) - p.width / 2, 0, std::int64_t(W - p.width)));
  p.y0 = std::uint32_t(std::clamp<std::int64_t>(std::int64_t(cy) - p.height / 2, 0, std::int64_t(H - p.height)));
  return p;
}

std::vector<PatchPlace> FurPatches::places(std::uint32_t view, std::uint32_t count, std::uint64_t seed) const {
  std::vector<PatchPlace> out;
  std::mt19937_64 rng(seed);
  for (std::uint32_t k = 0; k < count; ++k) {
    const PatchPlace p = place(view, rng());
    if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);
  }
  return out;
}

FurView FurPatches::cut(std::uint32_t view, const PatchPlace& p) const {
  const Stored& s = views_.at(view);
  NF_CHECK(p.x0 + p.width <= s.crop.width && p.y0 + p.height <= s.crop.height && p.width > 0 && p.height > 0,
           "fur patches: a patch outside its view");
  FurView v;
  v.camera = s.camera;
  v.crop = io::scaled_crop(s.crop, 1, 1, p.x0, p.y0, p.width, p.height);
  v.scale = 1;
  v.orientation_reliability = s.reliability;
  const std::uint64_t n = v.pixels();
  v.mask.assign(n, 0.f), v.silhouette_weight.assign(n, 1.f), v.orientation_weight.assign(n, 0.f);
  v.gabor_angle.assign(n, 0.f), v.gabor_confidence.assign(n, 0.f);
  std::vector<Texel> row(p.width);  // before the file is open: nothing to leak if it throws
  const int fd = ::open(s.file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(system_error(s.file, "cannot read the view's native targets back"));
  const std::size_t bytes = std::size_t(p.width) * sizeof(Texel);
  for (std::uint32_t y = 0; y < p.height; ++y) {
    const off_t at = off_t((std::uint64_t(p.y0 + y) * s.crop.width + p.x0) * sizeof(Texel));
    if (::pread(fd, row.data(), bytes, at) != ssize_t(bytes)) {
      ::close(fd);
      throw InputError(system_error(s.file, "cannot read the view's native targets back (was it removed?)"));
    }
    for (std::uint32_t x = 0; x < p.width; ++x) {
      const std::size_t o = std::size_t(y) * p.width + x;
      const Texel& t = row[x];
      const bool mask = t.flags & NativeTargets::kMask, fur = t.flags & NativeTargets::kFur;
      v.mask[o] = mask ? 1.f : 0.f;
      v.silhouette_weight[o] = mask && !fur ? 0.f : 1.f;  // 1 - (mask - fur): no silhouette on bald parts
      v.orientation_weight[o] = t.flags & NativeTargets::kOriented ? 1.f : 0.f;
      v.gabor_confidence[o] = float(t.reliability) / 255.f;
      v.gabor_angle[o] = float(double(t.angle) * M_PI / 65536.0);
    }
  }
  ::close(fd);
  v.body_depth = defur::camera_depth(gpu_, bald_, v.crop);
  return v;
}

}  // namespace nf::fur
