#pragma once
// The paper's prompts (supplementary, *Prompting*), word for word, in the order it asks them, each
// followed by one "Answer format:" line of ours so that any model answers in a form that can be
// read back. The direction prompt also says how the axes are drawn on the second image.
#include <string>
#include <vector>

namespace nf::knowledge {

struct Prompt {
  std::string step;    // length, thickness, verify, direction, eyes
  std::string text;    // the paper's words
  std::string format;  // our answer-format line
  std::string message() const { return text + "\n\nAnswer format: " + format; }
};

const std::string& system_prompt();
// The five prompts, in order. The first one is sent with the two images.
const std::vector<Prompt>& paper_prompts();
// Sent once when an answer cannot be read: what was wrong and the format again.
std::string repair_prompt(const std::string& problem, const Prompt& prompt);

}  // namespace nf::knowledge
