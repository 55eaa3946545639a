// Knowledge files: the presets carry the paper's table, round-trip through knowledge.json, and bad
// files are refused with the region and field named.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/knowledge/knowledge.hpp"

using namespace nf;
using namespace nf::knowledge;
using body::Region;

TEST_CASE("presets: every animal, every region, the paper's lengths") {
  for (const std::string animal : {"cat", "dog", "fox", "panda", "tiger", "lion"}) {
    CAPTURE(animal);
    const Knowledge k = preset(animal);
    CHECK(k.animal == animal);
    CHECK(k.source == "preset:" + animal);
    CHECK(k.eye_distance_cm > 1.0f);
    // A hair, not the fur layer: tenths of a millimetre at most.
    CHECK(k.hair_diameter_mm > 0.02f);
    CHECK(k.hair_diameter_mm < 0.2f);
    for (int r = 0; r < body::kRegionCount; ++r) {
      const Region region = static_cast<Region>(r);
      if (region == Region::mane) continue;
      CAPTURE(body::kRegionNames[r]);
      REQUIRE(k.has(region));
      CHECK(std::fabs(glm::length(k.at(region).direction) - 1.0f) < 1e-5f);
    }
    CHECK(!k.grows_fur(Region::eyes));
    CHECK(!k.grows_fur(Region::nosetip));
    CHECK(k.grows_fur(Region::body));
  }
  // Spot checks against the supplementary table (cm).
  CHECK(preset("cat").at(Region::tail).length_cm == doctest::Approx(1.35));
  CHECK(preset("dog").at(Region::ears).length_cm == doctest::Approx(1.8));
  CHECK(preset("fox").at(Region::tail).length_cm == doctest::Approx(7.8));
  CHECK(preset("panda").at(Region::belly).length_cm == doctest::Approx(7.5));
  CHECK(preset("tiger").at(Region::mane).length_cm == doctest::Approx(7));
  CHECK(!preset("cat").has(Region::mane));
  CHECK(preset("lion").grows_fur(Region::mane));
  CHECK(preset("lion").hair_diameter_mm_of(Region::mane) > preset("lion").hair_diameter_mm_of(Region::body));  // a mane's coarser hair
  CHECK_THROWS_WITH_AS(preset("unicorn"), doctest::Contains("presets: cat"), UsageError);
}

TEST_CASE("knowledge.json round-trips") {
  const auto path = std::filesystem::temp_directory_path() / "nf_knowledge_roundtrip.json";
  const Knowledge k = preset("fox");
  write_knowledge(path, k);
  const Knowledge r = read_knowledge(path);
  CHECK(r.animal == k.animal);
  CHECK(r.eye_distance_cm == k.eye_distance_cm);
  CHECK(r.hair_diameter_mm == k.hair_diameter_mm);
  for (int i = 0; i < body::kRegionCount; ++i) {
    REQUIRE(r.regions[i].has_value() == k.regions[i].has_value());
    if (!k.regions[i]) continue;
    CHECK(r.regions[i]->length_cm == k.regions[i]->length_cm);
    CHECK(r.regions[i]->thickness_cm == k.regions[i]->thickness_cm);
    CHECK(glm::distance(r.regions[i]->direction, k.regions[i]->direction) < 1e-6f);
    CHECK(r.regions[i]->hair_diameter_mm == k.regions[i]->hair_diameter_mm);
  }
  write_knowledge(path, preset("lion"));
  CHECK(*read_knowledge(path).at(Region::mane).hair_diameter_mm == doctest::Approx(0.15));
  std::filesystem::remove(path);
}

TEST_CASE("bad knowledge names the region and the field") {
  const auto base = [] {
    return json{{"animal", "cat"}, {"eye_distance_cm", 3.2},
                {"regions", {{"tail", {{"length_cm", 1.0}, {"thickness_cm", 0.3}, {"direction", {0, 0, -1}}}}}}};
  };
  CHECK_NOTHROW(knowledge_from_json(base(), "k.json"));
  json j = base();
  j["regions"]["wing"] = j["regions"]["tail"];
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("regions.wing: unknown region"), InputError);
  j = base();
  j["regions"]["nose_tip"] = j["regions"]["tail"];  // a near miss is named
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("did you mean 'nosetip'"), InputError);
  j = base();
  j["regions"]["tail"].erase("length_cm");
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("regions.tail: missing field 'length_cm'"), InputError);
  j = base();
  j["regions"]["tail"]["length_cm"] = -2.0;
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("regions.tail.length_cm"), InputError);
  j = base();
  j["regions"]["tail"]["direction"] = {0, 0, 0};
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("direction is the zero vector, but the region grows"), InputError);
  // A bald region's [0, 0, 0] is a normal answer: nothing grows along it.
  j["regions"]["tail"]["length_cm"] = 0.0, j["regions"]["tail"]["thickness_cm"] = 0.0;
  CHECK(knowledge_from_json(j, "k.json").at(Region::tail).direction == glm::vec3(0, -1, 0));
  j = base();
  j["regions"]["tail"]["direction"] = {0, "up", 0};
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("direction[1]"), InputError);
  // The hair's diameter is optional (files written before it existed), and checked when given.
  CHECK(knowledge_from_json(base(), "k.json").hair_diameter_mm == kDefaultHairDiameterMm);
  j = base();
  j["hair_diameter_mm"] = 35.0;  // 3.5 cm: a fur layer's thickness, not a hair
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("hair_diameter_mm = 35"), InputError);
  j = base();
  j["regions"]["tail"]["hair_diameter_mm"] = 0.0;
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("regions.tail.hair_diameter_mm"), InputError);
  j = base();
  j.erase("eye_distance_cm");
  CHECK_THROWS_WITH_AS(knowledge_from_json(j, "k.json"), doctest::Contains("eye_distance_cm"), InputError);
  const auto path = std::filesystem::temp_directory_path() / "nf_knowledge_bad.json";
  std::ofstream(path) << "{ \"animal\": ";
  CHECK_THROWS_WITH_AS(read_knowledge(path), doctest::Contains("not valid JSON"), InputError);
  std::filesystem::remove(path);
  CHECK_THROWS_WITH_AS(read_knowledge(path), doctest::Contains("cannot open"), InputError);
  // A region without an entry is named when asked for.
  CHECK_THROWS_WITH_AS(knowledge_from_json(base(), "k.json").at(Region::face), doctest::Contains("'face'"), InputError);
}
