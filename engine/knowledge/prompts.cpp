#include "engine/knowledge/prompts.hpp"

namespace nf::knowledge {

const std::string& system_prompt() {
  static const std::string text =
      "You are helping to reconstruct a furry animal in 3D from photos. Answer each question about the animal in "
      "the images. Give numbers as plain numbers (centimetres for lengths and thicknesses) and use the body part "
      "names exactly as the question spells them.";
  return text;
}

const std::vector<Prompt>& paper_prompts() {
  static const std::vector<Prompt> prompts = {
      {"length",
       "Here, you could see images of an animal. Could you estimate the accurate fur length in cm for each part of the "
       "animal: \"leg_front\", \"leg_rear\", \"paws\",  \"front_paws\",   \"belly\",   \"neck\",    \"face\",   "
       "\"ears\",      \"under_tail\",  \"tail\", \"body\", \"paw_pads\", \"inner_earcanal\", \"eyes\", "
       "\"nosetip\"? Also, does this animal have some fur near the neck that grows significantly beyond the underlying "
       "body? If so, could you add the estimates for length and fur thickness as well for \"mane\"  and include it at "
       "the end of the previous part names; otherwise, do not include it.  Is the ear canal visible in the image? If "
       "the inner ear canal is not visible, use the same value for length as for the outer ear. Please provide results "
       "in dict format, where the key is part name and the value is your estimate.",
       "one JSON object, {\"part name\": fur length in cm, ...}, e.g. {\"body\": 2.0, \"tail\": 3.5}."},
      {"thickness",
       "I want to create a furless animal. To do that, I have a 3D model of an animal with fur, from which I want to "
       "subtract the region covered by fur for each part. Could you provide the number of effective fur thickness for "
       "each part that I need to subtract from the full geometry? Please provide results in dict format where the key "
       "is part name and the value is your estimate.",
       "one JSON object, {\"part name\": effective fur thickness in cm, ...}."},
      {"verify",
       "Are you sure of the initial length estimations and fur thickness to abstract? Could you double-check with the "
       "image? Please provide results in a several-dict format where the key is part name and the value is your "
       "estimate.",
       "one JSON object with two dicts, {\"length\": {\"part name\": cm, ...}, \"thickness\": {\"part name\": cm, "
       "...}}."},
      {"direction",
       "Could you also estimate what the fur growing direction looks like in 3d space? I want to know which parts are "
       "oriented along the gravity vector and which are against. Also, if fur for regions grows from left to right or "
       "from right to left. I have the following coordinate system: x from the right side of animal towards the left, "
       "y - opposite to gravity direction, and z from back to the front of the animal. The second image is aligned "
       "with the 3D coordinate system. I want for each part: \"leg_front\", \"leg_rear\", \"paws\",  \"front_paws\",  "
       " \"belly\",   \"neck\",    \"face\",   \"ears\",      \"under_tail\",  \"tail\", \"body\", \"paw_pads\", "
       "\"inner_earcanal\", \"eyes\", \"nosetip\", \"mane\" (if appeared) obtains a vector that defines the "
       "approximate growing direction in the coordinate system. Please double-check the proposed directions several "
       "times.\n(In the second image the axes are drawn as arrows: x in red, y in green, z in blue.)",
       "one JSON object, {\"part name\": [x, y, z], ...}, e.g. {\"tail\": [0, -0.2, -1]}."},
      {"eyes",
       "Could you measure the distance between eyeballs in cm? You could also use the real-world  understanding of "
       "this animal class.",
       "one JSON object, {\"eye_distance_cm\": number}."},
      // Not the paper's: the exported strands' width is a hair's, not the fur layer's depth.
      {"hair",
       "What is the diameter of a single hair of this animal's coat, at its root, in millimetres? Use the real-world "
       "understanding of this animal class.",
       "one JSON object, {\"hair_diameter_mm\": number}."},
      // Not the paper's: a second cue for the metric scale beside the eyes (metric_scale.hpp).
      {"body",
       "What is the typical head-and-body length of an adult of this animal, from the tip of the nose to the base of "
       "the tail (the tail not included), in centimetres? Use the real-world understanding of this animal class, and "
       "of its breed if you can tell it.",
       "one JSON object, {\"body_length_cm\": number}."},
  };
  return prompts;
}

std::string repair_prompt(const std::string& problem, const Prompt& prompt) {
  return "I could not use that answer: " + problem + ". Please answer the last question again. Answer format: " +
         prompt.format;
}

}  // namespace nf::knowledge
