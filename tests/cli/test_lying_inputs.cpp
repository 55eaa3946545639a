// Inputs that lie: scenes whose files say one thing and mean another. Each must either work or end
// with exit code 1 and a message that names the file and says what to do (issue: reliability).
// Every case starts from the same small synthetic cat and changes one thing; the surface stage
// (the first that reads the photos and masks) runs on it with few steps.
#include <doctest/doctest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "tests/support/nf_process.hpp"

namespace fs = std::filesystem;
using nf::json;
using namespace nf::test;

namespace {

const std::string kNeus =
    " --quality draft --set neus.steps=30 --set neus.rays=128 --set neus.samples_per_ray=16 --set neus.fine_samples=8"
    " --set neus.hull_fit_steps=5 --set neus.mesh_resolution=32 --set neus.hull_resolution=48 --to neus";

bool has(const Result& r, const std::string& text) { return r.output.find(text) != std::string::npos; }

Result surface(const fs::path& scene) {
  const fs::path work = scene.parent_path() / (scene.filename().string() + "_work");
  fs::remove_all(work);
  return run("reconstruct --scene " + scene.string() + " --out " + work.string() + kNeus);
}

// A PNG with 16 bits per sample (grey or RGB), which stb cannot write: IHDR, one IDAT, IEND.
void write_png16(const fs::path& file, const nf::io::Image& image) {
  const std::uint32_t channels = image.channels >= 3 ? 3 : 1;
  std::string raw;
  for (std::uint32_t y = 0; y < image.height; ++y) {
    raw.push_back(0);  // filter: none
    for (std::uint32_t x = 0; x < image.width; ++x)
      for (std::uint32_t c = 0; c < channels; ++c) {
        const float v = image.pixels[(std::size_t(y) * image.width + x) * image.channels + c];
        const auto s = std::uint16_t(std::lround(std::clamp(v, 0.f, 1.f) * 65535.f));
        raw.push_back(char(s >> 8)), raw.push_back(char(s & 0xff));
      }
  }
  uLongf packed_size = compressBound(uLong(raw.size()));
  std::string packed(packed_size, '\0');
  REQUIRE(compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, reinterpret_cast<const Bytef*>(raw.data()),
                    uLong(raw.size()), 6) == Z_OK);
  packed.resize(packed_size);
  const auto be32 = [](std::uint32_t v) { return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; };
  const auto chunk = [&](const std::string& type, const std::string& data) {
    const std::string body = type + data;
    return be32(std::uint32_t(data.size())) + body +
           be32(std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
  };
  const std::string header = be32(image.width) + be32(image.height) + std::string{16, char(channels == 3 ? 2 : 0), 0, 0, 0};
  spit(file, std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", header) + chunk("IDAT", packed) + chunk("IEND", ""));
}

json transforms(const fs::path& scene) { return json::parse(slurp(scene / "transforms.json")); }
void save(const fs::path& scene, const json& t) { spit(scene / "transforms.json", t.dump(2)); }

}  // namespace

TEST_CASE("inputs that lie either work or end with a message naming the file") {
  const fs::path root = fs::temp_directory_path() / "nf_lying_inputs";
  fs::remove_all(root);
  const fs::path cat = root / "cat";
  REQUIRE(run("synth --animal cat --views 8 --res 64 --strands 3000 --spp-axis 1 --out " + cat.string()).code == 0);
  const auto copy_of = [&](const std::string& name) {
    const fs::path to = root / name;
    fs::copy(cat, to, fs::copy_options::recursive);
    return to;
  };

  SUBCASE("every mask empty") {
    const fs::path scene = copy_of("empty_masks");
    for (const auto& e : fs::directory_iterator(scene / "masks")) {
      nf::io::Image m = nf::io::read_image(e.path());
      std::fill(m.pixels.begin(), m.pixels.end(), 0.f);
      nf::io::write_png(e.path(), m);
    }
    const Result r = surface(scene);
    CHECK(r.code == 1);
    CHECK_MESSAGE(has(r, "every mask is empty (" + (scene / "masks").string()), r.output);
  }

  SUBCASE("the masks of another animal") {
    // The lion's masks from the same cameras: a consistent hull of the wrong shape. The surface
    // follows the masks, and the log says they do not fit the photos.
    const fs::path lion = root / "lion";
    REQUIRE(run("synth --animal lion --views 8 --res 64 --strands 3000 --spp-axis 1 --out " + lion.string()).code == 0);
    const fs::path scene = copy_of("other_masks");
    fs::remove_all(scene / "masks");
    fs::copy(lion / "masks", scene / "masks");
    const Result r = surface(scene);
    if (r.code == 0) CHECK_MESSAGE(has(r, "check that each mask belongs to its photo"), r.output);
    else CHECK_MESSAGE((r.code == 1 && has(r, "mask")), r.output);
  }

  SUBCASE("masks in the wrong order") {
    // Each photo gets the mask of the camera three places on: the hull is empty (an error naming a
    // camera and its mask) or, if some region survives, the log says the masks do not fit.
    const fs::path scene = copy_of("shuffled_masks");
    std::vector<fs::path> masks;
    for (const auto& e : fs::directory_iterator(scene / "masks")) masks.push_back(e.path());
    std::sort(masks.begin(), masks.end());
    std::vector<std::string> bytes;
    for (const fs::path& m : masks) bytes.push_back(slurp(m));
    for (std::size_t i = 0; i < masks.size(); ++i) spit(masks[i], bytes[(i + 3) % masks.size()]);
    const Result r = surface(scene);
    if (r.code == 0) CHECK_MESSAGE(has(r, "check that each mask belongs to its photo"), r.output);
    else CHECK_MESSAGE((r.code == 1 && has(r, "mask " + (scene / "masks").string())), r.output);
  }

  SUBCASE("photos with alpha and no mask: the alpha is the mask") {
    const fs::path scene = copy_of("alpha");
    json t = transforms(scene);
    for (json& f : t["frames"]) {
      const fs::path image = scene / f["file_path"].get<std::string>(), mask = scene / f["mask_path"].get<std::string>();
      const nf::io::Image rgb = nf::io::read_image(image), m = nf::io::read_image(mask);
      nf::io::Image rgba{rgb.width, rgb.height, 4, std::vector<float>(std::size_t(rgb.width) * rgb.height * 4)};
      for (std::size_t i = 0; i < std::size_t(rgb.width) * rgb.height; ++i) {
        for (int c = 0; c < 3; ++c) rgba.pixels[4 * i + c] = rgb.pixels[i * rgb.channels + c];
        rgba.pixels[4 * i + 3] = m.pixels[i * m.channels];
      }
      nf::io::write_png(image, rgba);
      f.erase("mask_path");
    }
    save(scene, t);
    fs::remove_all(scene / "masks");
    const Result r = surface(scene);
    CHECK_MESSAGE(r.code == 0, r.output);
    CHECK_MESSAGE(has(r, "alpha channel as the mask"), r.output);
  }

  SUBCASE("16-bit PNG photos and masks") {
    const fs::path scene = copy_of("png16");
    for (const char* folder : {"images", "masks"})
      for (const auto& e : fs::directory_iterator(scene / folder)) write_png16(e.path(), nf::io::read_image(e.path()));
    REQUIRE(nf::io::read_image(scene / "images" / "000.png").width == 64);
    const Result r = surface(scene);
    CHECK_MESSAGE(r.code == 0, r.output);
  }

  SUBCASE("EXR masks") {
    const fs::path scene = copy_of("exr_masks");
    json t = transforms(scene);
    for (json& f : t["frames"]) {
      const fs::path mask = scene / f["mask_path"].get<std::string>();
      const fs::path exr = fs::path(mask).replace_extension(".exr");
      nf::io::Image m = nf::io::read_image(mask);
      nf::io::write_exr(exr, m);
      fs::remove(mask);
      f["mask_path"] = fs::relative(exr, scene).generic_string();
    }
    save(scene, t);
    const Result r = surface(scene);
    CHECK_MESSAGE(r.code == 0, r.output);
  }

  SUBCASE("a camera inside the animal") {
    const fs::path scene = copy_of("inside");
    json t = transforms(scene);
    // Camera 0 moved into the middle of the animal (the centroid of its true outer surface).
    const nf::geometry::Mesh outer = nf::io::read_mesh(scene / "gt" / "outer.ply");
    glm::dvec3 centre(0.0);
    for (std::uint64_t v = 0; v < outer.vertex_count(); ++v) centre += glm::dvec3(outer.position(v));
    centre /= double(outer.vertex_count());
    for (int r = 0; r < 3; ++r) t["frames"][0]["transform_matrix"][r][3] = centre[r];
    save(scene, t);
    const Result r = surface(scene);
    CHECK(r.code == 1);
    CHECK_MESSAGE(has(r, scene.string() + ": camera '000' sits inside the animal"), r.output);
    CHECK_MESSAGE(has(r, "Its pose is wrong"), r.output);
  }

  SUBCASE("two views") {
    const fs::path scene = root / "two";
    REQUIRE(run("synth --animal cat --views 2 --res 64 --strands 3000 --spp-axis 1 --out " + scene.string()).code == 0);
    const Result r = surface(scene);
    CHECK_MESSAGE((r.code == 0 || (r.code == 1 && has(r, "transforms.json"))), r.output);
  }

  SUBCASE("four hundred views") {
    const fs::path scene = root / "many";
    REQUIRE(run("synth --animal cat --views 400 --res 32 --strands 2000 --spp-axis 1 --out " + scene.string()).code == 0);
    const Result r = surface(scene);
    CHECK_MESSAGE(r.code == 0, r.output);
  }
  fs::remove_all(root);
}
