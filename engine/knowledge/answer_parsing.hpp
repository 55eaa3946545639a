#pragma once
// Reading a vision-language model's free-text answers: the JSON object or Python dict inside prose
// and markdown fences, region names in any reasonable spelling, and numbers with or without units.
// Nothing here trusts the answer: every value is checked and every error names the prompt, the
// region and the field.
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"

namespace nf::knowledge {

// The objects ({...}) in `text`, in order, as JSON: each parsed as JSON or, failing that, as a
// Python dict literal (single quotes, True/False/None, tuples, trailing commas). Objects nested in
// another are part of it, not listed again. `labels[i]` is the text between the previous object
// (or the start) and object i, lower-cased, e.g. "effective thickness:".
struct FoundObject {
  json value;
  std::string label;
};
std::vector<FoundObject> find_objects(const std::string& text);

// The region a name from an answer means: exact names, common synonyms ("hind legs", "inner ear",
// "nose"), any case, spaces or hyphens for underscores, and small misspellings. nullopt when it
// matches nothing.
std::optional<body::Region> match_region(const std::string& name);

// A length in cm from a number or a string such as "2", "2.5 cm", "25 mm", "2-3 cm" (the middle),
// "~1.5cm". Throws InputError "<where>: ..." for anything else (NaN, text, a list).
double length_cm_of(const json& value, const std::string& where);

// A direction from [x, y, z], {"x":..,"y":..,"z":..}, "(0, -1, 0)" or an axis word ("down", "-y",
// "forward"...), normalised. Throws InputError "<where>: ..." when it is none of these, not finite,
// or zero (with `allow_zero`, zero comes back as the zero vector).
glm::vec3 direction_of(const json& value, const std::string& where, bool allow_zero = false);

// Per-region values of one answer.
template <class T>
struct RegionValues {
  std::vector<std::pair<body::Region, T>> values;
  std::vector<std::string> unknown;  // names that match no region (ignored)
};

// {region: value} from an answer object. `hints` are words of the wanted field ("length", or
// "thick"): the function descends into the wrapping object whose key has one ({"lengths": {...}},
// {"thickness": {...}}) or into a single wrapping object, and picks the matching field of
// per-region objects ({"body": {"length": 2, "thickness": 1}}). Errors name "<where>: regions.R.<field>".
// Keys with a word of `exclude` belong to another field ("mane_thickness" among lengths) and are
// skipped; values that say "not given" (null, "N/A") are left out for the fill rules.
RegionValues<double> region_lengths(const json& object, const std::vector<std::string>& hints,
                                    const std::vector<std::string>& exclude, const std::string& field, const std::string& where);
RegionValues<glm::vec3> region_directions(const json& object, const std::string& where);

// The eye distance in cm from an answer: a JSON field whose name has "eye" or "distance" in it, else
// the first number with a unit (cm or mm) in the text. Throws InputError when there is none.
double eye_distance_cm_of(const std::string& text, const std::string& where);
// A hair's diameter in mm from the answer to the hair prompt: a JSON field (a bare number is mm) or
// the first length with a unit in prose (mm, um, cm).
double hair_diameter_mm_of(const std::string& text, const std::string& where);
// The head-and-body length in cm from the answer to the body prompt: a JSON field whose name has
// "length" or "body" (not "tail") in it, else the first length with a unit in the text.
double body_length_cm_of(const std::string& text, const std::string& where);

}  // namespace nf::knowledge
