// libFuzzer target: a VLM's answers on arbitrary bytes, through the whole annotation (objects in
// prose, Python dicts, region names, lengths, directions, the eye distance, the fill rules).
#include <string>

#include "engine/core/error.hpp"
#include "engine/knowledge/vlm_annotation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string answer(reinterpret_cast<const char*>(data), size);
  const nf::knowledge::ChatFunction chat = [&](const nf::json&, const std::string&) { return answer; };
  try {
    (void)nf::knowledge::annotate_with_vlm(chat, {"data:,", "data:,"}, "fuzz");
  } catch (const nf::Error&) {
  }
  return 0;
}
