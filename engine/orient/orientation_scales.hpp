#pragma once
// Gabor orientation at several scales, and how far each pixel's orientation can be trusted.
//
// The Gabor bank has a fixed width (sigma_x 1.8 px across a strand, a 4.3 px period): it sees
// strands that are 1-3 photo pixels wide. A strand is as many pixels wide as the photo is large,
// so a 4096 px photo's strands are too wide for the bank that fits a 1024 px photo's. Each scale s
// filters the photo halved s times; per pixel the scale whose orientation is most reliable wins
// (the finer one on a tie), so one photo can hold fine fur on the face and coarse fur on the back.
//
// Reliability: the coherence of the Gabor map's doubled-angle vectors (weighted by the filters'
// confidence) in a window of `window` pixels of that scale, centred on the pixel and clipped at the
// image's border, above the coherence as many random orientations would show (2 / sqrt(pixels)),
// clamped to [0, 1]. Gabor maps of textureless fur (sub-pixel strands, smooth shading) answer with
// confident but incoherent angles; this keeps them at 0.
#include <cstdint>
#include <functional>
#include <vector>

#include "engine/io/image.hpp"
#include "engine/orient/orientation_map.hpp"

namespace nf::orient {

// Summed-area tables of a map's confidence-weighted doubled-angle vectors and of its confidences:
// the reliability of any window in O(1).
class OrientationSums {
 public:
  explicit OrientationSums(const OrientationMap& map);
  // The reliability above of the window [x0, x1) x [y0, y1) (0 where it holds no confidence, and
  // for windows of 4 pixels or fewer, where as many random orientations look coherent).
  double reliability(std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1) const;

 private:
  double box(const std::vector<double>& table, std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1) const;
  std::size_t stride_ = 1;
  std::vector<double> x_, y_, c_;
};

// Per pixel of `map`, the reliability of the window centred on it; its half is window / 2.
std::vector<float> orientation_reliability(const OrientationMap& map, std::uint32_t window);

// The image halved by a 2 x 2 box (an odd last row or column keeps its own pixels); a mask pixel
// of the halved image is set when any of its pixels is.
io::Image halve(const io::Image& image);
std::vector<std::uint8_t> halve_mask(const std::vector<std::uint8_t>& mask, std::uint32_t width, std::uint32_t height);

struct ScaledOrientation {
  std::uint32_t width = 0, height = 0;
  std::vector<float> angle, reliability;  // per pixel of the full image
  std::vector<std::uint8_t> scale;        // the scale that won: 0 the image itself, s halved s times
};

// The map of an image under a mask (the GPU's gabor_orientation, or the CPU reference in tests).
using OrientationOf = std::function<OrientationMap(const io::Image& image, const std::vector<std::uint8_t>& mask)>;

// `scales` >= 1 scales (halving stops when a side would fall below 16 px). `finest`: the image's
// own map when the caller has it already (not recomputed). A coarser scale may win only at least
// `outline` of its own pixels inside its mask (outline x 2^s image pixels): nearer, its filters
// answer the mask's edge against the background, which is more coherent than any fur; the image's
// own scale near the outline is the caller's to mask. InputError for scales 0 or a mask of the
// wrong size.
ScaledOrientation scaled_orientation(const io::Image& image, const std::vector<std::uint8_t>& mask, std::uint32_t scales,
                                     std::uint32_t window, const OrientationOf& orientation_of, std::uint32_t outline = 0,
                                     const OrientationMap* finest = nullptr);

// The mask eroded by `radius` pixels: set where the (2 radius + 1)^2 box around the pixel lies in
// the image and holds no unset pixel.
std::vector<std::uint8_t> eroded_mask(const std::vector<std::uint8_t>& mask, std::uint32_t width, std::uint32_t height,
                                      std::uint32_t radius);

}  // namespace nf::orient
