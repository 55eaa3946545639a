#pragma once
// Gabor orientation maps of photos on the GPU (NeuralFur's orientation supervision, after Paris et
// al. 2004 and Neural Haircut): per pixel the strand orientation and a confidence. Maths, formula
// and angle convention: gabor_ref.hpp and gabor_bank.hpp. GPU passes (--profile):
// "orient/dog_prefilter" and "orient/gabor".
#include <cstdint>
#include <vector>

#include "engine/gpu/context.hpp"
#include "engine/io/image.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

struct OrientationMap {
  // Radians in [0, pi): the strand direction, from +x (right) towards -y (up on screen), i.e.
  // counter-clockwise as seen on screen. 0 outside the mask.
  io::Image orientation;
  // sqrt(sum_i d_i^2 (F_i - F_max)^2 / sum_i d_i^2), in Gabor-response units; 0 outside the mask.
  io::Image confidence;
};

// Grey value the filters see: 0.2989 R + 0.5870 G + 0.1140 B of the stored (usually sRGB-encoded)
// values, the reference's rgb2gray; 1- and 2-channel images use their first channel.
std::vector<float> luminance(const io::Image& image);

// Orientation map of `image` (any channel count). mask: width * height bytes, nonzero = compute;
// null = every pixel. Throws InputError on an empty image, a mask of the wrong size, NaN/Inf pixels
// or bad parameters. Images too large for one storage-buffer binding are processed in bands of
// rows with enough overlap that the result is identical.
OrientationMap gabor_orientation(gpu::Context& context, const io::Image& image, const std::vector<std::uint8_t>* mask,
                                 const GaborParams& params = {});

}  // namespace nf::orient
