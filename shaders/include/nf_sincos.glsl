// sin and cos of large arguments: reduce modulo 2 pi in three parts (Cody-Waite) before calling
// the builtins, which are only specified on [-pi, pi]. The split keeps k * C1 and k * C2 exact for
// |k| < 2^17, i.e. |t| < 8e5 (frequency encodings of |x| <= 1e3 at 2^9). CPU twin:
// engine/nn/frequency_encoding_ref.hpp.
#ifndef NF_SINCOS_GLSL
#define NF_SINCOS_GLSL

const float NF_TWO_PI_1 = 6.25;                  // 5 significant bits
const float NF_TWO_PI_2 = 0.033203125;           // 5 significant bits
const float NF_TWO_PI_3 = -1.7817820120692e-05;  // the rest of 2 pi
const float NF_INV_TWO_PI = 0.15915494309189535;

float nf_reduce_two_pi(float t) {
  const float k = floor(t * NF_INV_TWO_PI + 0.5);
  return ((t - k * NF_TWO_PI_1) - k * NF_TWO_PI_2) - k * NF_TWO_PI_3;
}

#endif
