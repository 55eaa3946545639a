#pragma once
// One annotation by a vision-language model: the paper's five prompts asked as one conversation
// (each answer stays in the conversation, so later prompts see it), every answer read and checked
// (lengths 0-60 cm, thickness <= length, finite non-zero directions, eyes 0.5-40 cm), a single
// "please answer again" when an answer cannot be used, and the regions the answers leave out filled
// by the rules of fill_missing_regions. Transport, caching and transcripts are the caller's (the
// `chat` function), so this is tested without a network.
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::knowledge {

struct AnnotationImages {
  std::string frontal, side_with_axes;  // data URLs (data:image/jpeg;base64,...)
};

// Sends `messages` (OpenAI chat format) and returns the assistant's text; `step` names the prompt
// ("length", "length-retry", ...) for the transcript.
using ChatFunction = std::function<std::string(const json& messages, const std::string& step)>;

struct Annotation {
  Knowledge knowledge;
  std::vector<std::string> warnings;  // filled regions, clamped thickness, ignored names
  std::map<std::string, std::string> origin;  // values that came from the fallback: field -> its source
  int requests = 0;
};

inline constexpr double kMaxLengthCm = 60, kMinEyeCm = 0.5, kMaxEyeCm = 40;

// An answer that stays unusable after one retry: with a `fallback` (the animal's preset), the
// values it refuses (a region's, or the whole field's when nothing reads) are the fallback's, each
// with a warning and an entry in the knowledge's `origin`; without one, InputError "<where>: the
// answer to the <step> prompt: ..." naming the region and field.
Annotation annotate_with_vlm(const ChatFunction& chat, const AnnotationImages& images, const std::string& where,
                             const Knowledge* fallback = nullptr);

// The regions an annotation lacks, filled from a related region (README, *Knowledge*): the inner
// ear canal from the ears (as the prompt says), paws and front paws from each other, each leg from
// the other, under_tail from tail, face from neck, every other furred region from body; eyes,
// nose tip and paw pads bald. A missing thickness is that of the region the length came from,
// else 0.35 x length (as the presets); a missing direction comes along the same chain of regions.
// mane stays absent unless answered. Each fill is one warning.
// Throws InputError when `body` itself has no length.
struct PartialKnowledge {
  std::array<std::optional<double>, body::kRegionCount> length, thickness;
  std::array<std::optional<glm::vec3>, body::kRegionCount> direction;
};
Knowledge fill_missing_regions(const PartialKnowledge& answers, std::vector<std::string>& warnings, const std::string& where);

}  // namespace nf::knowledge
