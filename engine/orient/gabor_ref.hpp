#pragma once
// CPU reference of the Gabor orientation maps: the same maths as the GPU kernels
// (shaders/orient/*.comp), written as plain loops in double precision. Tests compare against it.
//
// Per pixel x inside the mask, with D the DoG-filtered grey image (gabor_bank.hpp) and g_i the
// filter of orientation theta_i = i pi / N:
//   F_i        = | sum_p g_i(p) D(x + p) |        absolute response: the even (cosine) filter gives
//                                                 a dark strand a negative response and a bright one
//                                                 a positive one, and on a grating the sign follows
//                                                 the local phase; |.| keeps all of them (the
//                                                 reference does the same), a positive rectification
//                                                 would leave half of every grating without a peak.
//   m          = argmax_i F_i                     (the first on ties)
//   orientation = theta_m
//   confidence  = sqrt( sum_i d(theta_i, theta_m)^2 (F_i - F_m)^2 / sum_i d(theta_i, theta_0)^2 )
// d = undirected angular distance in radians, in [0, pi/2]. This is Paris et al. 2004's measure
// sqrt(sum d^2 (F - F_m)^2) divided by the constant sqrt(sum d^2), so that it reads in response
// units: F_m for a bank whose only response is at theta_m, 0 for a flat response (and for a flat
// image, where Neural Haircut's normalised variance sum d^2 F / sum F is 0/0). It scales with the
// image contrast, like the Gabor responses. Outside the mask orientation and confidence are 0.
#include <cstdint>
#include <vector>

#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

// D = G_low * grey - G_high * grey, separable, edges clamped. grey: width * height, row-major.
std::vector<double> dog_prefilter_ref(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height,
                                      const GaborParams& params);

struct OrientationRef {
  std::vector<float> orientation, confidence;  // width * height
  std::vector<double> responses;               // [pixel][orientation] F_i, when asked for
};

// mask: width * height, nonzero = inside; null = every pixel.
OrientationRef gabor_orientation_ref(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height,
                                     const std::vector<std::uint8_t>* mask, const GaborParams& params,
                                     bool keep_responses = false);

}  // namespace nf::orient
