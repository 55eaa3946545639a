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

#include "engine/io/strands.hpp"

namespace nf::io {

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
StrandSet read_strands_usda(const std::filesystem::path& path);

// By extension (.hair, .ply, .obj, .usda); throws InputError for others.
void write_strands(const std::filesystem::path& path, const StrandSet& strands);
StrandSet read_strands(const std::filesystem::path& path);

}  // namespace nf::io
