// Cem Yuksel's .hair format (cemyuksel.com/research/hairmodels): a 128-byte header, then the
// arrays its bit field announces, in order: segments (uint16 per strand), points, thickness,
// transparency, colours (float32).
#include <cmath>
#include <algorithm>
#include <cstring>
#include <fstream>
#include <memory>

#include "engine/core/atomic_file.hpp"
#include "engine/io/binary_io.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/strand_stream.hpp"

namespace nf::io {
namespace {

constexpr std::uint32_t kSegments = 1, kPoints = 2, kThickness = 4, kTransparency = 8, kColors = 16;

#pragma pack(push, 1)
struct HairHeader {
  char signature[4];
  std::uint32_t hair_count;
  std::uint32_t point_count;
  std::uint32_t arrays;
  std::uint32_t default_segments;
  float default_thickness;
  float default_transparency;
  float default_color[3];
  char info[88];
};
#pragma pack(pop)
static_assert(sizeof(HairHeader) == 128);

}  // namespace

void write_hair(const std::filesystem::path& path, const StrandSet& s) {
  s.validate(path.string());
  HairHeader h{};
  std::memcpy(h.signature, "HAIR", 4);
  h.hair_count = s.strand_count();
  h.point_count = std::uint32_t(s.point_count());
  h.arrays = kSegments | kPoints | (s.thickness.empty() ? 0u : kThickness) |
             (s.transparency.empty() ? 0u : kTransparency) | (s.colors.empty() ? 0u : kColors);
  h.default_segments = 0;
  h.default_thickness = 1.f;
  h.default_transparency = 0.f;
  h.default_color[0] = h.default_color[1] = h.default_color[2] = 1.f;
  std::strncpy(h.info, ("nf_gpu strands; " + std::string(frame_marker(FileFrame::scene))).c_str(), sizeof h.info - 1);
  std::vector<std::uint16_t> segments(s.strand_count());
  for (std::uint32_t i = 0; i < s.strand_count(); ++i) {
    const std::uint32_t n = s.points_in(i);
    if (n < 1 || n > 65536)
      throw InputError(path.string() + ": strand " + std::to_string(i) + " has " + std::to_string(n) +
                       " points; .hair stores 1..65536 per strand");
    segments[i] = std::uint16_t(n - 1);
  }
  write_file_atomic(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    write_array(out, segments);
    write_array(out, s.points);
    write_array(out, s.thickness);
    write_array(out, s.transparency);
    write_array(out, s.colors);
  });
}

void write_uniform_hair(const std::filesystem::path& path, std::uint32_t strands, std::uint32_t points_per_strand,
                        const std::function<void(const std::function<void(std::span<const float>)>&)>& produce) {
  StrandStream stream;
  stream.strands = strands;
  stream.points = std::uint64_t(strands) * points_per_strand;
  stream.points_in = [points_per_strand](std::uint64_t) { return points_per_strand; };
  stream.each_chunk = produce;
  write_hair(path, stream);
}

void write_hair(const std::filesystem::path& path, const StrandStream& s) {
  if (s.points > 0xffffffffull || s.strands > 0xffffffffull)
    throw InputError(path.string() + ": " + std::to_string(s.strands) + " strands of " + std::to_string(s.points) +
                     " points exceed the .hair header's 32-bit counts");
  // One segment count for all strands goes in the header; otherwise the segments array.
  bool uniform = true;
  std::uint32_t first_count = s.strands ? s.points_in(0) : 1;
  std::uint64_t total = 0;
  for (std::uint64_t i = 0; i < s.strands; ++i) {
    const std::uint32_t n = s.points_in(i);
    if (n < 1 || n > 65536)
      throw InputError(path.string() + ": strand " + std::to_string(i) + " has " + std::to_string(n) + " points; .hair stores 1..65536 per strand");
    uniform = uniform && n == first_count;
    total += n;
  }
  if (total != s.points) throw InternalError(path.string() + ": the strands hold " + std::to_string(total) + " points, not " + std::to_string(s.points));
  HairHeader h{};
  std::memcpy(h.signature, "HAIR", 4);
  h.hair_count = std::uint32_t(s.strands);
  h.point_count = std::uint32_t(s.points);
  h.arrays = kPoints | (uniform ? 0u : kSegments) | (s.width ? kThickness : 0u) | (s.color ? kColors : 0u);
  h.default_segments = uniform ? first_count - 1 : 0;
  h.default_thickness = 1.f;
  h.default_color[0] = h.default_color[1] = h.default_color[2] = 1.f;
  std::strncpy(h.info, ("nf_gpu strands; " + std::string(frame_marker(s.frame))).c_str(), sizeof h.info - 1);
  write_file_atomic(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    if (!uniform)
      for (std::uint64_t i = 0; i < s.strands; ++i) {
        const std::uint16_t segments = std::uint16_t(s.points_in(i) - 1);
        out.write(reinterpret_cast<const char*>(&segments), 2);
      }
    std::uint64_t floats = 0;  // counted in floats: write_uniform_hair's chunks need not hold whole points
    s.each_chunk([&](std::span<const float> xyz) {
      require_finite_points(path, xyz, floats);
      if (floats + xyz.size() > 3 * s.points) throw InternalError(path.string() + ": more points than the header announced");
      out.write(reinterpret_cast<const char*>(xyz.data()), std::streamsize(xyz.size() * 4));
      floats += xyz.size();
    });
    if (floats != 3 * s.points)
      throw InternalError(path.string() + ": " + std::to_string(floats / 3) + " points written, the header announced " + std::to_string(s.points));
    if (s.width)
      for (std::uint64_t i = 0; i < s.strands; ++i)
        for (std::uint32_t k = 0, n = s.points_in(i); k < n; ++k) {
          const float w = s.width(i, k);
          out.write(reinterpret_cast<const char*>(&w), 4);
        }
    if (s.color)  // (the format's colour array follows the thickness and transparency arrays)
      for (std::uint64_t i = 0; i < s.strands; ++i)
        for (std::uint32_t k = 0, n = s.points_in(i); k < n; ++k) {
          const glm::vec3 c = s.color(i, k);
          out.write(reinterpret_cast<const char*>(&c.x), 12);
        }
  });
}

StrandStream stream_hair_file(const std::filesystem::path& path, std::uint64_t chunk_points) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where + ": cannot open");
  HairHeader h;
  if (!in.read(reinterpret_cast<char*>(&h), sizeof h)) throw InputError(where + ": shorter than the 128-byte .hair header");
  if (std::memcmp(h.signature, "HAIR", 4) != 0) throw InputError(where + ": not a .hair file (signature 'HAIR' missing)");
  if (!(h.arrays & kPoints)) throw InputError(where + ": header says the file has no points array");
  const std::uint64_t size = std::filesystem::file_size(path);
  const std::uint64_t segments_bytes = (h.arrays & kSegments) ? 2ull * h.hair_count : 0;
  if (sizeof h + segments_bytes + 12ull * h.point_count > size)
    throw InputError(where + ": header counts (" + std::to_string(h.hair_count) + " strands, " + std::to_string(h.point_count) +
                     " points) need more bytes than the file holds (truncated, or a count is wrong)");
  if (h.hair_count > h.point_count) throw InputError(where + ": hair count " + std::to_string(h.hair_count) + " exceeds the point count " + std::to_string(h.point_count));
  auto counts = std::make_shared<std::vector<std::uint16_t>>();
  if (h.arrays & kSegments) {
    counts->resize(h.hair_count);
    in.read(reinterpret_cast<char*>(counts->data()), std::streamsize(segments_bytes));
  } else if (h.default_segments + 1ull > 65536) {
    throw InputError(where + ": default segment count " + std::to_string(h.default_segments) + " is invalid");
  }
  std::uint64_t total = 0;
  for (std::uint64_t i = 0; i < h.hair_count; ++i) total += (counts->empty() ? h.default_segments : (*counts)[i]) + 1ull;
  if (total != h.point_count)
    throw InputError(where + ": strands hold " + std::to_string(total) + " points but the header says " + std::to_string(h.point_count));
  StrandStream s;
  s.strands = h.hair_count;
  s.points = h.point_count;
  const std::uint32_t uniform = h.default_segments + 1;
  s.points_in = [counts, uniform](std::uint64_t i) { return counts->empty() ? uniform : std::uint32_t((*counts)[i]) + 1; };
  const std::uint64_t offset = sizeof h + segments_bytes, points = h.point_count;
  chunk_points = std::max<std::uint64_t>(1, chunk_points);
  s.each_chunk = [path, where, offset, points, chunk_points](const PointSink& sink) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw InputError(where + ": cannot open");
    file.seekg(std::streamoff(offset));
    std::vector<float> buffer;
    for (std::uint64_t done = 0; done < points;) {
      const std::uint64_t n = std::min(chunk_points, points - done);
      buffer.resize(3 * n);
      if (!file.read(reinterpret_cast<char*>(buffer.data()), std::streamsize(12 * n)))
        throw InputError(where + ": ended while reading point " + std::to_string(done) + " (the file changed while being read?)");
      sink(std::span<const float>(buffer));
      done += n;
    }
  };
  return s;
}

StrandSet read_hair(const std::filesystem::path& path) {
  const std::string where = path.string();
  const std::vector<char> bytes = read_file_bytes(path);
  ByteReader in(bytes, where);
  HairHeader h;
  in.read(&h, 1, "header");
  if (std::memcmp(h.signature, "HAIR", 4) != 0) throw InputError(where + ": not a .hair file (signature 'HAIR' missing)");
  if (!(h.arrays & kPoints)) throw InputError(where + ": header says the file has no points array");
  if (!(h.arrays & kSegments) && h.default_segments + 1ull > 65536)
    throw InputError(where + ": default segment count " + std::to_string(h.default_segments) + " is invalid");
  // Before allocating anything: do the counts fit in the file at all?
  const std::uint64_t per_point = 12 + ((h.arrays & kThickness) ? 4 : 0) + ((h.arrays & kTransparency) ? 4 : 0) +
                                  ((h.arrays & kColors) ? 12 : 0);
  const std::uint64_t need = ((h.arrays & kSegments) ? 2ull * h.hair_count : 0) + per_point * h.point_count;
  if (need > in.remaining())
    throw InputError(where + ": header counts (" + std::to_string(h.hair_count) + " strands, " +
                     std::to_string(h.point_count) + " points) need " + std::to_string(need) + " bytes but " +
                     std::to_string(in.remaining()) + " follow the header (truncated, or a count is wrong)");
  if (h.point_count && !h.hair_count) throw InputError(where + ": points but no strands");
  if (h.hair_count > h.point_count)  // every strand has a point: this also bounds the allocation below
    throw InputError(where + ": hair count " + std::to_string(h.hair_count) + " exceeds the point count " +
                     std::to_string(h.point_count));
  StrandSet s;
  s.offsets.resize(std::size_t(h.hair_count) + 1, 0);
  std::vector<std::uint16_t> segments(h.hair_count, std::uint16_t(h.default_segments));
  if (h.arrays & kSegments) in.read(segments.data(), segments.size(), "segments array");
  for (std::uint32_t i = 0; i < h.hair_count; ++i) s.offsets[i + 1] = s.offsets[i] + segments[i] + 1u;
  if (s.offsets.back() != h.point_count)
    throw InputError(where + ": strands hold " + std::to_string(s.offsets.back()) + " points but the header says " +
                     std::to_string(h.point_count));
  s.points.resize(std::size_t(h.point_count) * 3);
  in.read(s.points.data(), s.points.size(), "points array");
  if (h.arrays & kThickness) {
    s.thickness.resize(h.point_count);
    in.read(s.thickness.data(), s.thickness.size(), "thickness array");
  }
  if (h.arrays & kTransparency) {
    s.transparency.resize(h.point_count);
    in.read(s.transparency.data(), s.transparency.size(), "transparency array");
  }
  if (h.arrays & kColors) {
    s.colors.resize(std::size_t(h.point_count) * 3);
    in.read(s.colors.data(), s.colors.size(), "color array");
  }
  if (in.remaining())
    throw InputError(where + ": " + std::to_string(in.remaining()) + " bytes follow the last array (counts disagree)");
  // Absent arrays take the header's defaults, when those differ from the format's neutral values.
  if (!(h.arrays & kThickness) && h.default_thickness != 1.f) s.thickness.assign(h.point_count, h.default_thickness);
  if (!(h.arrays & kTransparency) && h.default_transparency != 0.f) s.transparency.assign(h.point_count, h.default_transparency);
  if (!(h.arrays & kColors) && (h.default_color[0] != 1.f || h.default_color[1] != 1.f || h.default_color[2] != 1.f))
    for (std::uint32_t p = 0; p < h.point_count; ++p) s.colors.insert(s.colors.end(), h.default_color, h.default_color + 3);
  s.validate(where);
  return s;
}

}  // namespace nf::io
