#pragma once
// The strand geometry map (strand_geometry.hpp) in the gradient-check catalog.
#include <memory>

#include "engine/fur/strand_geometry_ref.hpp"
#include "engine/gradcheck/harness.hpp"

namespace nf::fur {

std::unique_ptr<gradcheck::DifferentiableKernel> make_strand_geometry_check();

// The check's inputs, shared with the checks of maps built on it (length_factors_gradcheck.hpp):
// the shape from a case's params (strands, segments, row_stride); decoder rows like the prior's
// (segments of about 1/S, noise, random padding); frames with roots around `origin` (spread
// `spread`), fur about `length` long and random orthonormal axes.
StrandGeometryShape strand_geometry_shape(const gradcheck::Params& p);
std::vector<double> strand_geometry_rows(std::uint32_t strands, std::uint32_t segments, std::uint32_t stride, unsigned seed);
std::vector<double> strand_geometry_frames(std::uint32_t strands, double origin, double spread, double length, unsigned seed);

}  // namespace nf::fur
