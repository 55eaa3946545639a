#include "engine/fur/fur_views.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "engine/core/error.hpp"
#include "engine/defur/nonbald_masks.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/orient/orientation_io.hpp"
#include "engine/orient/orientation_map.hpp"
#include "engine/orient/orientation_scales.hpp"

namespace nf::fur {
namespace {

orient::OrientationMap true_orientation_of(const io::Scene& scene, const io::Camera& cam) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(scene.root);
  if (!gt || !std::filesystem::exists(gt->orientation(cam.name)))
    throw InputError("fur.orientation_target=truth needs " + (gt ? gt->orientation(cam.name) : scene.root / "gt" / "orientation").string() +
                     ": a synth scene written with --true-orientation");
  orient::OrientationMap map = orient::read_orientation_exr(gt->orientation(cam.name));
  if (map.orientation.width != cam.width || map.orientation.height != cam.height)
    throw InputError(gt->orientation(cam.name).string() + ": not the size of camera '" + cam.name + "'");
  return map;
}

}  // namespace

FurView make_fur_view(gpu::Context& gpu, const io::Scene& scene, std::uint32_t camera, const io::Image* nonbald,
                      const geometry::Mesh& bald, const FurViewOptions& options, NativeTargets* native) {
  const io::Camera& cam = scene.cameras.at(camera);
  const io::Image photo = io::read_image(cam.image);
  if (photo.width != cam.width || photo.height != cam.height)
    throw InputError(cam.image.string() + ": " + std::to_string(photo.width) + "x" + std::to_string(photo.height) +
                     " pixels, but camera '" + cam.name + "' is " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  const std::vector<std::uint8_t> mask = io::mask_of(io::read_image(cam.mask));
  if (mask.size() != std::size_t(cam.width) * cam.height)
    throw InputError(cam.mask.string() + ": the mask does not have camera '" + cam.name + "''s size");
  if (nonbald && (nonbald->width != cam.width || nonbald->height != cam.height))
    throw InputError("fur: the non-bald mask of camera '" + cam.name + "' does not have the camera's size (rerun the defur stage)");
  const orient::OrientationMap gabor = options.true_orientation ? true_orientation_of(scene, cam) : orient::gabor_orientation(gpu, photo, &mask, options.gabor);
  // The mask eroded by the outline band: no orientation target where the filters see the outline.
  const int outline = options.outline_px >= 0 ? options.outline_px
                                              : int(std::ceil(options.gabor.support * std::max(options.gabor.sigma_x, options.gabor.sigma_y)));
  const std::vector<std::uint8_t> inner = orient::eroded_mask(mask, cam.width, cam.height, std::uint32_t(std::max(0, outline)));

  // The rendering grid and the mask's box on it.
  const std::uint32_t side = std::max(cam.width, cam.height);
  const double scale = options.max_side && side > options.max_side ? double(options.max_side) / side : 1.0;
  const std::uint32_t W = std::max(1u, std::uint32_t(std::lround(cam.width * scale))), H = std::max(1u, std::uint32_t(std::lround(cam.height * scale)));
  const double sx = double(W) / cam.width, sy = double(H) / cam.height;
  std::uint32_t bx0 = cam.width, by0 = cam.height, bx1 = 0, by1 = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y)
    for (std::uint32_t x = 0; x < cam.width; ++x)
      if (mask[std::size_t(y) * cam.width + x]) bx0 = std::min(bx0, x), by0 = std::min(by0, y), bx1 = std::max(bx1, x + 1), by1 = std::max(by1, y + 1);
  if (bx1 == 0) throw InputError(cam.mask.string() + ": the mask of camera '" + cam.name + "' is empty");
  const auto lo = [&](std::uint32_t v, double s) { return std::uint32_t(std::max(0.0, std::floor(v * s) - options.margin_px)); };
  const auto hi = [&](std::uint32_t v, double s, std::uint32_t n) { return std::uint32_t(std::min<double>(n, std::ceil(v * s) + options.margin_px)); };
  const std::uint32_t x0 = lo(bx0, sx), y0 = lo(by0, sy), x1 = hi(bx1, sx, W), y1 = hi(by1, sy, H);

  const orient::OrientationSums sums(gabor);  // the reliability of any window in O(1)

  FurView v;
  v.camera = camera;
  v.crop = io::scaled_crop(cam, sx, sy, x0, y0, x1 - x0, y1 - y0);
  v.scale = std::sqrt(sx * sy);
  const std::uint64_t n = v.pixels();
  v.mask.assign(n, 0.f), v.silhouette_weight.assign(n, 0.f), v.orientation_weight.assign(n, 0.f);
  v.gabor_angle.assign(n, 0.f), v.gabor_confidence.assign(n, 0.f), v.rgb.assign(3 * n, 0.f);
  for (std::uint32_t y = 0; y < v.crop.height; ++y)
    for (std::uint32_t x = 0; x < v.crop.width; ++x) {
      // The photo pixels whose centres fall in this rendering pixel.
      const std::uint32_t px0 = std::uint32_t(std::ceil((x + x0) / sx - 0.5)), px1 = std::uint32_t(std::ceil((x + x0 + 1) / sx - 0.5));
      const std::uint32_t py0 = std::uint32_t(std::ceil((y + y0) / sy - 0.5)), py1 = std::uint32_t(std::ceil((y + y0 + 1) / sy - 0.5));
      double m = 0, fur = 0, fur_inner = 0, ox = 0, oy = 0, count = 0, rgb[3] = {0, 0, 0};
      for (std::uint32_t py = py0; py < std::min(py1, cam.height); ++py)
        for (std::uint32_t px = px0; px < std::min(px1, cam.width); ++px) {
          const std::size_t i = std::size_t(py) * cam.width + px;
          const double inside = mask[i] ? 1.0 : 0.0;
          m += inside;
          const double grows = nonbald ? double(nonbald->pixels[i * nonbald->channels] > 0.5f) : 1.0;
          fur += inside * grows;
          fur_inner += (inner[i] ? 1.0 : 0.0) * grows;
          const double a = gabor.orientation.pixels[i], c = gabor.confidence.pixels[i];
          ox += c * std::cos(2 * a), oy += c * std::sin(2 * a);
          for (std::uint32_t ch = 0; ch < 3; ++ch) rgb[ch] += photo.pixels[i * photo.channels + std::min(ch, photo.channels - 1)];
          count += 1;
        }
      const std::size_t o = std::size_t(y) * v.crop.width + x;
      if (count == 0) { v.silhouette_weight[o] = 1.f; continue; }
      m /= count, fur /= count, fur_inner /= count, ox /= count, oy /= count;
      for (std::uint32_t ch = 0; ch < 3; ++ch) v.rgb[3 * o + ch] = float(rgb[ch] / count);
      v.mask[o] = float(m);
      v.silhouette_weight[o] = float(1.0 - (m - fur));
      v.orientation_weight[o] = float(fur_inner);
      double angle = 0.5 * std::atan2(oy, ox);
      if (angle < 0) angle += M_PI;
      v.gabor_angle[o] = float(angle);
      // Reliability: the coherence of the orientations in a window of at least coherence_px photo
      // pixels about this pixel's footprint, above what as many random orientations would show.
      const std::uint32_t half = options.coherence_px / 2;
      const std::uint32_t wx0 = std::min(px0, (px0 + px1) / 2 > half ? (px0 + px1) / 2 - half : 0u);
      const std::uint32_t wy0 = std::min(py0, (py0 + py1) / 2 > half ? (py0 + py1) / 2 - half : 0u);
      const std::uint32_t wx1 = std::min(cam.width, std::max(px1, (px0 + px1) / 2 + half + 1));
      const std::uint32_t wy1 = std::min(cam.height, std::max(py1, (py0 + py1) / 2 + half + 1));
      v.gabor_confidence[o] = float(sums.reliability(wx0, wy0, wx1, wy1));
    }
  double reliable = 0, fur_pixels = 0;
  for (std::uint64_t p = 0; p < n; ++p) reliable += double(v.orientation_weight[p]) * v.gabor_confidence[p], fur_pixels += v.orientation_weight[p];
  v.orientation_reliability = fur_pixels > 0 ? reliable / fur_pixels : 0.0;
  v.body_depth = defur::camera_depth(gpu, bald, v.crop);
  if (native) {
    // The same box as the view's crop: its margin counted in photo pixels.
    const std::uint32_t margin = std::uint32_t(std::ceil(options.margin_px / v.scale));
    const std::uint32_t nx0 = bx0 > margin ? bx0 - margin : 0, ny0 = by0 > margin ? by0 - margin : 0;
    const std::uint32_t nx1 = std::min(cam.width, bx1 + margin), ny1 = std::min(cam.height, by1 + margin);
    // The scales are chosen on the box only, padded by what the coarsest scale's filters read (the
    // band-pass and the bank, 2^(scales - 1) photo pixels each), so they see what they would in
    // the whole photo: no work on the photo's pixels far from the animal.
    const std::uint32_t reach = options.gabor_scales > 1 ? std::uint32_t(orient::gaussian_half_taps(options.gabor.dog_high_sigma).size() +
                                                                         std::size_t(orient::make_gabor_bank(options.gabor).radius))
                                                                << (options.gabor_scales - 1)
                                                          : 0u;
    // (The corner on the coarsest scale's grid, so the halvings pair the pixels the photo's would.)
    const std::uint32_t grid = ~((1u << (std::max(1u, options.gabor_scales) - 1)) - 1u);
    const std::uint32_t px0 = (nx0 > reach ? nx0 - reach : 0) & grid, py0 = (ny0 > reach ? ny0 - reach : 0) & grid;
    const std::uint32_t px1 = std::min(cam.width, nx1 + reach), py1 = std::min(cam.height, ny1 + reach), pw = px1 - px0;
    std::vector<std::uint8_t> padded_mask(std::size_t(pw) * (py1 - py0));
    for (std::uint32_t y = py0; y < py1; ++y)
      std::copy_n(mask.begin() + std::ptrdiff_t(std::size_t(y) * cam.width + px0), pw, padded_mask.begin() + std::ptrdiff_t(std::size_t(y - py0) * pw));
    const orient::OrientationMap padded_gabor{io::crop(gabor.orientation, px0, py0, px1, py1), io::crop(gabor.confidence, px0, py0, px1, py1)};
    const orient::ScaledOrientation scaled = orient::scaled_orientation(
        io::crop(photo, px0, py0, px1, py1), padded_mask, options.gabor_scales, options.coherence_px,
        [&](const io::Image& image, const std::vector<std::uint8_t>& m) { return orient::gabor_orientation(gpu, image, &m, options.gabor); },
        std::uint32_t(std::max(0, outline)), &padded_gabor);
    NativeTargets& t = *native;
    t.crop = io::scaled_crop(cam, 1, 1, nx0, ny0, nx1 - nx0, ny1 - ny0);
    const std::uint64_t count = t.pixels();
    t.flags.assign(count, 0), t.angle.assign(count, 0.f), t.confidence.assign(count, 0.f), t.scale.assign(count, 0);
    for (std::uint32_t y = 0; y < t.crop.height; ++y)
      for (std::uint32_t x = 0; x < t.crop.width; ++x) {
        const std::size_t i = std::size_t(y + ny0) * cam.width + x + nx0, o = std::size_t(y) * t.crop.width + x;
        const bool grows = !nonbald || nonbald->pixels[i * nonbald->channels] > 0.5f;
        t.flags[o] = std::uint8_t((mask[i] ? NativeTargets::kMask : 0) | (mask[i] && grows ? NativeTargets::kFur : 0) |
                                  (inner[i] && grows ? NativeTargets::kOriented : 0));
        const std::size_t at = std::size_t(y + ny0 - py0) * pw + x + nx0 - px0;
        t.angle[o] = scaled.angle[at], t.confidence[o] = scaled.reliability[at], t.scale[o] = scaled.scale[at];
      }
  }
  return v;
}

}  // namespace nf::fur
