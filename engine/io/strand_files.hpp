#pragma once
// Strand files for DCC tools, written atomically (temporary name, then rename) straight from the
// StrandSet's arrays (no second copy of the data), and read back with every count and size checked
// against the file (errors name the file and the field):
//   .hair  Cem Yuksel's binary format: all optional arrays (segments, thickness, transparency,
//          colour). It has no field for regions; they are not stored.
//   .ply   binary little-endian: vertex chains as `edge` elements (what Blender imports), plus a
//          `strand` element (first vertex, count, region) that keeps strands exact.
//   .obj   `v` lines and one `l` polyline per strand.
//   .usda  a USD BasisCurves prim (linear), widths per vertex, region as a uniform primvar.
// Little-endian hosts only (x86-64, arm64), checked at compile time.
#include <filesystem>
#include <functional>
#include <span>
#include <string>

#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"
#include "engine/io/strands.hpp"

namespace nf::io {

struct StrandStream;

void write_hair(const std::filesystem::path& path, const StrandSet& strands);
StrandSet read_hair(const std::filesystem::path& path);
// A .hair file of `strands` strands of `points_per_strand` points each (the header's default count,
// no segments array), whose points `produce` hands over in order, in chunks of any size: memory
// does not grow with the strand count. InputError for a non-finite point (the file is not
// written); InternalError when the chunks do not add up to the announced count.
void write_uniform_hair(const std::filesystem::path& path, std::uint32_t strands, std::uint32_t points_per_strand,
                        const std::function<void(const std::function<void(std::span<const float>)>&)>& produce);

void write_strands_ply(const std::filesystem::path& path, const StrandSet& strands);
StrandSet read_strands_ply(const std::filesystem::path& path);

void write_strands_obj(const std::filesystem::path& path, const StrandSet& strands);
StrandSet read_strands_obj(const std::filesystem::path& path);

// default_width is used where the set has no thickness (scene units).
void write_strands_usda(const std::filesystem::path& path, const StrandSet& strands, float default_width = 0.0025f);

// Streamed writers (strand_stream.hpp): the points are asked for once and never held whole.
// .hair gets a thickness array from the widths; .ply a thickness property; .usda widths per vertex.
void write_hair(const std::filesystem::path& path, const StrandStream& strands);
void write_strands_ply(const std::filesystem::path& path, const StrandStream& strands);
void write_strands_obj(const std::filesystem::path& path, const StrandStream& strands);
// What a .usda groom holds beside the curves: the unit, the body as a Mesh prim "body" (normals and
// `region` per vertex when present) and, per curve, the body face and barycentric coordinates of its
// root (uniform primvars rootFace, rootBarycentric) so the fur can follow the skin.
struct UsdaScene {
  double meters_per_unit = 0;  // stated in the layer's metadata when > 0
  const geometry::Mesh* body = nullptr;
  std::span<const float> body_colors;  // linear RGB per body vertex (primvars:displayColor), or empty
  std::function<std::uint32_t(std::uint64_t)> root_face;
  std::function<glm::vec3(std::uint64_t)> root_barycentric;
};
// Under a root Xform "animal" (the default prim, Y up): BasisCurves "fur" (linear, nonperiodic,
// extent, widths per vertex when the stream has them, `region` uniform) and the UsdaScene's parts.
void write_strands_usda(const std::filesystem::path& path, const StrandStream& strands, const UsdaScene& scene = {});
StrandSet read_strands_usda(const std::filesystem::path& path);

// By extension (.hair, .ply, .obj, .usda); throws InputError for others.
void write_strands(const std::filesystem::path& path, const StrandSet& strands);
StrandSet read_strands(const std::filesystem::path& path);

}  // namespace nf::io
