#pragma once
// `nf_gpu render`: shaded previews of strands over the body for people to look at, traced by the
// Embree renderer of strand_renderer.hpp.
//
// Colours: strands take a fixed palette colour per body region (region_palette()): the strand's own
// region when the strand file carries regions, else the region of the body vertex nearest to the
// strand's root when the mesh carries regions, else the palette's `body` colour. The body is a
// neutral grey so the fur stands out.
// Strand radius: 0.5 x the scene's median pixel footprint at the animal's distance, times
// `width_scale`. The footprint of a camera is depth / ((fx + fy) / 2), with depth the distance along
// its viewing axis to the centre of the body mesh's bounding box; the median runs over every camera
// of the scene (cameras that see the centre behind them are skipped), so the radius does not depend
// on the views chosen. A strand is thus about one pixel wide at the animal.
// Output: `<out>/<camera name>.png` (sRGB, the camera's size), each written atomically; the folder
// is created when missing, is never inside the scene folder, and no file in it that nf_gpu did not
// write is replaced. Names are made file-safe (characters
// other than letters, digits, '.', '-' and '_' become '_'); a name shared by several cameras gets
// the camera index appended.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"

namespace nf::synth {

struct PreviewOptions {
  std::filesystem::path strands;  // any strand format of engine/io/strand_files.hpp
  std::filesystem::path mesh;     // body mesh (.ply, .obj, .glb, .gltf); regions used when present
  std::filesystem::path scene;    // any scene format of engine/io/scene.hpp
  std::filesystem::path out;      // output folder
  std::string views = "all";      // "all" or comma-separated camera indices, e.g. "0,5,9"
  std::uint32_t samples_per_axis = 3;  // anti-aliasing: s x s samples per pixel
  double width_scale = 1.0;            // multiplies the default strand radius
};

struct PreviewResult {
  std::vector<std::filesystem::path> files;  // one per rendered view, in the order of `views`
  float strand_radius = 0;                   // scene units
  std::string coloring;                      // "strand regions", "nearest body vertex region" or "single colour"
  double seconds = 0;
};

// sRGB colours, indexed by region id (body::Region).
const std::array<glm::vec3, body::kRegionCount>& region_palette();
// A region's palette colour (the `body` colour for an id outside the table), and sRGB -> linear
// (what the renderer's looks take).
glm::vec3 palette_color(std::int64_t region);
glm::vec3 linear(glm::vec3 srgb);


// Reads the inputs (InputError naming the file and field when one is missing or malformed),
// renders the chosen views and writes them. UsageError for bad option values.
PreviewResult render_previews(const PreviewOptions& options);

// A mesh shaded in its regions' palette colours (no strands) from the given cameras, written as
// `<out>/<camera name>.png`: how a stage shows its labels to people. Returns the files.
// The same renders, returned instead of written (sRGB, 3 channels), for a stage to compose.
std::vector<io::Image> render_region_images(const geometry::Mesh& mesh, const io::Scene& scene,
                                            const std::vector<std::uint32_t>& views);
std::vector<std::filesystem::path> render_region_previews(const geometry::Mesh& mesh, const io::Scene& scene,
                                                          const std::vector<std::uint32_t>& views,
                                                          const std::filesystem::path& out);

}  // namespace nf::synth
