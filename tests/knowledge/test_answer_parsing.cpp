// Reading a VLM's answers: objects inside prose, fences and Python syntax; region names in other
// spellings; lengths with units and ranges; directions as lists, objects, tuples or words; the eye
// distance in prose. Every refusal names the region and the field.
#include <doctest/doctest.h>

#include "engine/core/error.hpp"
#include "engine/knowledge/answer_parsing.hpp"

using namespace nf;
using namespace nf::knowledge;
using body::Region;

TEST_CASE("objects are found in prose, markdown fences and Python syntax") {
  const auto found = find_objects("Sure! Here are my estimates:\n```json\n{\"body\": 2.5, \"tail\": {\"x\": 1}}\n```\nHope it helps.");
  REQUIRE(found.size() == 1);
  CHECK(found[0].value["body"] == 2.5);
  CHECK(found[0].value["tail"]["x"] == 1);

  const auto py = find_objects("{'leg_front': 1.5, 'ears': (0, 1, 0), 'mane': None, 'ok': True, 'note': \"cat's fur\",}");
  REQUIRE(py.size() == 1);
  CHECK(py[0].value["leg_front"] == 1.5);
  CHECK(py[0].value["ears"] == json::array({0, 1, 0}));
  CHECK(py[0].value["mane"].is_null());
  CHECK(py[0].value["ok"] == true);
  CHECK(py[0].value["note"] == "cat's fur");

  // Two dicts, labelled by the words before them; bare words and numbers with units become text.
  const auto two = find_objects("Lengths:\n{body: 2cm, tail: 3}\nEffective thickness:\n{'body': .5, 'tail': -.25}");
  REQUIRE(two.size() == 2);
  CHECK(two[0].label.find("lengths") != std::string::npos);
  CHECK(two[0].value["body"] == "2cm");
  CHECK(two[1].label.find("thickness") != std::string::npos);
  CHECK(two[1].value["body"] == 0.5);
  CHECK(two[1].value["tail"] == -0.25);

  CHECK(find_objects("no dict here, {only braces").empty());
  CHECK(find_objects("").empty());
}

TEST_CASE("region names in other spellings") {
  CHECK(match_region("leg_front") == Region::leg_front);
  CHECK(match_region("Leg Front") == Region::leg_front);
  CHECK(match_region("front legs") == Region::leg_front);
  CHECK(match_region("Hind-Legs") == Region::leg_rear);
  CHECK(match_region("Inner_EarCanal") == Region::inner_earcanal);
  CHECK(match_region("inner ear") == Region::inner_earcanal);
  CHECK(match_region("Nose tip") == Region::nosetip);
  CHECK(match_region("nostip") == Region::nosetip);      // a misspelling
  CHECK(match_region("under-tail") == Region::under_tail);
  CHECK(match_region("body fur length") == Region::body);
  CHECK(match_region("MANE") == Region::mane);
  CHECK_FALSE(match_region("whiskers"));
  CHECK_FALSE(match_region("length"));
  CHECK_FALSE(match_region(""));
}

TEST_CASE("lengths: numbers, units, ranges; anything else is refused with its place") {
  CHECK(length_cm_of(json(2.5), "x") == doctest::Approx(2.5));
  CHECK(length_cm_of(json("2.5 cm"), "x") == doctest::Approx(2.5));
  CHECK(length_cm_of(json("25mm"), "x") == doctest::Approx(2.5));
  CHECK(length_cm_of(json("2-3 cm"), "x") == doctest::Approx(2.5));
  CHECK(length_cm_of(json("2 to 3 centimeters"), "x") == doctest::Approx(2.5));
  CHECK(length_cm_of(json("~1.5cm"), "x") == doctest::Approx(1.5));
  CHECK(length_cm_of(json("about 1 inch"), "x") == doctest::Approx(2.54));
  CHECK_THROWS_WITH_AS(length_cm_of(json("NaN"), "regions.body.length_cm"), doctest::Contains("regions.body.length_cm: 'NaN'"), InputError);
  CHECK_THROWS_WITH_AS(length_cm_of(json("long"), "regions.tail.length_cm"), doctest::Contains("regions.tail.length_cm"), InputError);
  CHECK_THROWS_AS(length_cm_of(json("3 furlongs"), "x"), InputError);
  CHECK_THROWS_AS(length_cm_of(json::array({1, 2}), "x"), InputError);
  CHECK_THROWS_AS(length_cm_of(json(nullptr), "x"), InputError);
}

TEST_CASE("directions: lists, objects, tuples in text, axis words; zero and junk refused") {
  CHECK(glm::distance(direction_of(json::array({0, -2, 0}), "d"), glm::vec3(0, -1, 0)) < 1e-6f);
  CHECK(glm::distance(direction_of(json{{"x", 0}, {"y", 0}, {"z", "-1"}}, "d"), glm::vec3(0, 0, -1)) < 1e-6f);
  CHECK(glm::distance(direction_of(json("(0, 1, 0)"), "d"), glm::vec3(0, 1, 0)) < 1e-6f);
  CHECK(glm::distance(direction_of(json("down"), "d"), glm::vec3(0, -1, 0)) < 1e-6f);
  CHECK(glm::distance(direction_of(json("backward and down"), "d"), glm::normalize(glm::vec3(0, -1, -1))) < 1e-6f);
  CHECK(glm::distance(direction_of(json("-z"), "d"), glm::vec3(0, 0, -1)) < 1e-6f);
  CHECK_THROWS_WITH_AS(direction_of(json::array({0, 0, 0}), "regions.body.direction"),
                       doctest::Contains("regions.body.direction: '[0,0,0]' is the zero vector"), InputError);
  CHECK_THROWS_WITH_AS(direction_of(json::array({"a", 0, 0}), "regions.tail.direction"),
                       doctest::Contains("regions.tail.direction[0]"), InputError);
  CHECK_THROWS_AS(direction_of(json::array({1e300, 0, 0}), "d"), InputError);
  CHECK_THROWS_AS(direction_of(json::array({1, 0}), "d"), InputError);
  CHECK_THROWS_AS(direction_of(json("sideways-ish"), "d"), InputError);
}

TEST_CASE("per-region tables: wrapped, nested, unknown names") {
  const json wrapped = json::parse(R"({"lengths": {"Body": 2, "front legs": "1.5 cm", "whiskers": 5}})");
  const auto v = region_lengths(wrapped, {"length"}, {"thick"}, "length_cm", "answer");
  REQUIRE(v.values.size() == 2);  // in key order
  CHECK(v.values[0].first == Region::body);
  CHECK(v.values[1].first == Region::leg_front);
  CHECK(v.values[1].second == doctest::Approx(1.5));
  REQUIRE(v.unknown.size() == 1);
  CHECK(v.unknown[0] == "whiskers");

  const json nested = json::parse(R"({"body": {"length": 2, "thickness": 0.7}, "tail": {"length": 3, "thickness": 1}})");
  CHECK(region_lengths(nested, {"thick"}, {"length"}, "thickness_cm", "a").values[1].second == doctest::Approx(1.0));
  const json both = json::parse(R"({"length": {"body": 2}, "thickness": {"body": 0.5}})");
  CHECK(region_lengths(both, {"thick"}, {"length"}, "thickness_cm", "a").values[0].second == doctest::Approx(0.5));
  CHECK(region_lengths(both, {"length"}, {"thick"}, "length_cm", "a").values[0].second == doctest::Approx(2.0));
  CHECK_THROWS_WITH_AS(region_lengths(json::parse(R"({"body": "lots"})"), {"length"}, {}, "length_cm", "the answer"),
                       doctest::Contains("the answer: regions.body.length_cm"), InputError);
  CHECK_THROWS_WITH_AS(region_lengths(json::parse(R"({"colour": "brown"})"), {"length"}, {}, "length_cm", "the answer"),
                       doctest::Contains("names no body region"), InputError);
  const auto dirs = region_directions(json::parse(R"({"directions": {"tail": [0, 0, -1], "ears": "up"}})"), "a");
  REQUIRE(dirs.values.size() == 2);  // in key order: ears, tail
  CHECK(dirs.values[0].first == Region::ears);
  CHECK(dirs.values[0].second.y == doctest::Approx(1.0));
}

TEST_CASE("the eye distance in a field or in prose") {
  CHECK(eye_distance_cm_of(R"({"eye_distance_cm": 3.2})", "eyes") == doctest::Approx(3.2));
  CHECK(eye_distance_cm_of("The distance between the eyeballs is about 3.5 cm for an adult cat.", "eyes") == doctest::Approx(3.5));
  CHECK(eye_distance_cm_of("Roughly 30-40 mm.", "eyes") == doctest::Approx(3.5));
  CHECK(eye_distance_cm_of("{'distance': '4 cm'}", "eyes") == doctest::Approx(4.0));
  CHECK_THROWS_WITH_AS(eye_distance_cm_of("I cannot tell from a photo.", "eyes"), doctest::Contains("no distance"), InputError);
}

TEST_CASE("hostile or ambiguous answers: meta keys, other fields, deep nesting, cut characters") {
  CHECK_FALSE(match_region("notes"));
  CHECK_FALSE(match_region("Comments"));
  CHECK_FALSE(match_region("rump"));   // four letters: no guessing
  CHECK_FALSE(match_region("toes"));
  CHECK(match_region("nosetp") == Region::nosetip);
  CHECK(match_region("under_tial") == Region::under_tail);
  CHECK(match_region("bellly") == Region::belly);
  CHECK_FALSE(match_region(std::string(100000, 'a')));
  // "mane_thickness" in a table of lengths is the mane's thickness, not its length.
  const json mane = json::parse(R"({"body": 2, "mane": 8, "mane_thickness": 3, "notes": "looks right"})");
  const auto v = region_lengths(mane, {"length"}, {"thick"}, "length_cm", "a");
  REQUIRE(v.values.size() == 2);
  CHECK(v.values[1].first == Region::mane);
  CHECK(v.values[1].second == doctest::Approx(8.0));
  // A wrapper of regions beside a region key: both read, the wrapper's values first.
  const json wrapped = json::parse(R"({"lengths": {"body": 2, "tail": 3}, "mane": {"length": 8, "thickness": 3}})");
  const auto w = region_lengths(wrapped, {"length"}, {"thick"}, "length_cm", "a");
  CHECK(w.values.size() == 3);
  // Values that say "not given" are left to the fill rules.
  CHECK(region_lengths(json::parse(R"({"body": 2, "mane": null, "tail": "N/A"})"), {"length"}, {}, "length_cm", "a").values.size() == 1);
  // 5,000 nested lists: refused as an object, not a crash.
  const std::string deep = "{\"body\": " + std::string(5000, '[') + std::string(5000, ']') + "}";
  CHECK(find_objects(deep).empty());
  // An error that quotes a long value cuts it between characters, so the message stays valid UTF-8.
  const std::string value = std::string(39, 'x') + "\xc3\xa9\xc3\xa9 long";
  try {
    length_cm_of(json(value), "regions.body.length_cm");
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK_NOTHROW((void)json(std::string(e.what())).dump());
  }
}
