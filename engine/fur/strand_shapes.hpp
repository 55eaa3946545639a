#pragma once
// Procedural fur strands for training and testing the strand prior: 100 points, root at the
// origin of its TBN frame (x: tangent T, y: bitangent B, z: the skin's normal N), unit arc length,
// made of 99 segments of equal length. The shapes span what fur does and more than `nf_gpu synth`
// grows: any lift from lying flat to standing straight, any heading on the skin, lying down or
// lifting towards the tip, sideways drift, smooth random bends, waves, helical curls and sag
// towards any gravity direction.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::fur {

inline constexpr std::uint32_t kStrandPoints = 100;
inline constexpr std::uint32_t kStrandSegments = kStrandPoints - 1;

// The style families the generator mixes; `Any` draws each feature independently.
enum class StrandStyle { Straight, LyingDown, Wavy, Curly, Sagging, Any };
const std::vector<StrandStyle>& strand_styles();  // every style but Any
std::string style_name(StrandStyle style);

// `count` strands of kStrandPoints points (xyz, root first) drawn with `seed`: a fixed seed gives
// the same strands on every machine (std::mt19937 and our own distributions).
std::vector<float> generate_strands(std::uint32_t count, std::uint64_t seed, StrandStyle style = StrandStyle::Any);

// A polyline of any number of points (xyz, root first) moved into the frame (root, T, B, N),
// resampled uniformly along its arc length to kStrandPoints points and scaled to unit length.
// Returns false for a strand without length.
bool strand_in_frame(const float* points, std::uint32_t count, const glm::vec3& root, const glm::vec3& tangent,
                     const glm::vec3& bitangent, const glm::vec3& normal, float* out);

// Mean and 95th percentile over strands of the mean distance between corresponding points, for
// unit-length strands: a share of the strand's length.
struct PointError {
  double mean = 0, p95 = 0;
};
PointError point_error(const std::vector<float>& predicted, const std::vector<float>& truth);

}  // namespace nf::fur
