#pragma once
// The filters of the Gabor orientation maps, built once on the host and shared by the GPU wrapper
// and the CPU reference, so both apply exactly the same weights.
//
// Angle convention (everywhere in engine/orient): image x to the right, y down; an orientation
// theta in [0, pi) is the direction of the strand (the stripe), measured from +x towards -y, i.e.
// counter-clockwise on screen. A line through (0,0) and (+1,-1) has theta = 45 degrees; the image
// direction (dx, dy) has theta = atan2(-dy, dx) mod pi (orientation_of_direction()).
// (Neural Haircut's maps store the carrier's direction, across the strands, in the same sense:
// their angle = ours + 90 degrees, mod 180.)
//
// Filter theta (NeuralFur / Neural Haircut bank: 180 orientations, sigma_x 1.8, sigma_y 2.4,
// frequency 0.23 cycles/px, as skimage.filters.gabor_kernel builds it, real part):
//   g_theta(p) = exp(-(a^2/sigma_x^2 + b^2/sigma_y^2) / 2) cos(2 pi f a) / (2 pi sigma_x sigma_y),
//   a = p . n (across the strand), b = p . t (along it), t = (cos theta, -sin theta),
//   n = (sin theta, cos theta), for integer offsets p with |p| <= support * max(sigma_x, sigma_y).
// The support is a disc, not skimage's per-theta box, so that truncation favours no orientation.
// g is even (g(p) = g(-p)): the bank stores one tap per pair {p, -p}, the centre first.
//
// Prefilter: difference of Gaussians G_low - G_high (skimage.filters.difference_of_gaussians(0.4,
// 10), as the reference does): a band-pass that removes the sensor noise below the fur's strand
// width and the shading above 10 px, which would otherwise dominate the filters' small DC gain.
// Each Gaussian is separable, truncated at radius int(4 sigma + 0.5) (scipy's default) and
// normalised to sum 1. Borders clamp to the edge (skimage's 'nearest' for the DoG; the reference's
// 'wrap' for the Gabor stage would mix opposite borders of a photo, so we clamp there too).
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::orient {

constexpr double kPi = 3.14159265358979323846;

struct GaborParams {
  float dog_low_sigma = 0.4f;    // px; 0 = no low-pass
  float dog_high_sigma = 10.f;   // px; 0 = nothing subtracted (low-pass only)
  std::uint32_t orientations = 180;
  float sigma_x = 1.8f;          // px, across the strand (along the carrier wave)
  float sigma_y = 2.4f;          // px, along the strand
  float frequency = 0.23f;       // cycles per pixel
  float support = 3.f;           // kernel radius in units of max(sigma_x, sigma_y)
  std::uint32_t band_rows = 0;   // GPU rows per band; 0 = as many as one buffer binding allows
  std::uint32_t pixels_per_invocation = 0;  // GPU tuning: 1, 2, 4 or 8; 0 = by device kind
};

// Throws InputError naming the bad field.
void validate(const GaborParams& params);

struct GaborTap {
  int dx = 0, dy = 0;  // one offset of the pair {p, -p}; tap 0 is the centre (0, 0)
};

struct GaborBank {
  std::uint32_t orientations = 0;
  int radius = 0;                  // max |dx|, |dy| over the taps: the apron a tile needs
  std::vector<GaborTap> taps;      // centre, then half-disc offsets (dy > 0, or dy == 0 and dx > 0)
  std::vector<double> weights;     // [orientation][tap]: g_theta(p)
  double theta(std::uint32_t i) const { return kPi * i / orientations; }
  double weight(std::uint32_t orientation, std::size_t tap) const { return weights[orientation * taps.size() + tap]; }
  // sum over the bins of d(theta_i, theta_m)^2, the same for every m: normalises the confidence.
  double distance2_sum = 0;
};

GaborBank make_gabor_bank(const GaborParams& params);

// Half of a symmetric, normalised Gaussian: taps[0] is the centre, taps[k] the weight at +-k.
// sigma 0 gives the identity {1}.
std::vector<double> gaussian_half_taps(float sigma);

// Undirected distance between orientations (radians), in [0, pi/2].
inline double orientation_distance(double a, double b) {
  const double d = std::fabs(std::remainder(a - b, kPi));
  return d;
}

// theta of the image-space direction (dx, dy) (x right, y down) in [0, pi); see the convention above.
inline double orientation_of_direction(double dx, double dy) {
  double t = std::atan2(-dy, dx);
  if (t < 0) t += kPi;
  if (t >= kPi) t -= kPi;
  return t;
}

}  // namespace nf::orient
