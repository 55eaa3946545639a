#pragma once
// A groom handed to the strand writers in chunks, so that writing N strands never holds their
// points in memory at once (an edit's millions of strands are as cheap to export as a test's ten):
// every writer asks for the points once, in order, and takes the per-strand and per-point
// attributes from functions. A StrandSet is one source; a .hair file read piece by piece is another.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include <glm/glm.hpp>

#include "engine/io/file_frame.hpp"
#include "engine/io/strands.hpp"

namespace nf::io {

using PointSink = std::function<void(std::span<const float> xyz)>;

struct StrandStream {
  std::uint64_t strands = 0, points = 0;
  std::function<std::uint32_t(std::uint64_t strand)> points_in;
  // Hands every point's xyz to `sink` in order, in chunks of whole points. Called once per writer.
  std::function<void(const PointSink& sink)> each_chunk;
  std::function<float(std::uint64_t strand, std::uint32_t k)> width;  // per point, scene units; empty: none
  std::function<std::int32_t(std::uint64_t strand)> region;           // empty: none
  std::function<glm::vec3(std::uint64_t strand, std::uint32_t k)> color;  // per point, linear RGB; empty: none
  FileFrame frame = FileFrame::scene;                                   // stated in the file (file_frame.hpp)

  // A view of `set` (which must outlive it): its thickness as widths, its regions and colours.
  static StrandStream of(const StrandSet& set);
};

// (strand, point within the strand) of each point, in the order the points stream: what a writer
// needs to store per-point attributes beside the points.
class StrandCursor {
 public:
  explicit StrandCursor(const StrandStream& s) : s_(s) { settle(); }
  std::uint64_t strand() const { return strand_; }
  std::uint32_t k() const { return k_; }
  void next() {
    ++k_;
    settle();
  }

 private:
  void settle() {  // skips strands without points
    while (strand_ < s_.strands && k_ >= (n_ ? n_ : (n_ = s_.points_in(strand_)))) {
      ++strand_, k_ = 0, n_ = 0;
    }
  }
  const StrandStream& s_;
  std::uint64_t strand_ = 0;
  std::uint32_t k_ = 0, n_ = 0;
};

// A .hair file read `chunk_points` points at a time: the header and segment counts are read and
// checked up front (InputError naming the file, as read_hair does), the points when asked. Its
// thickness, transparency and colours are not streamed.
StrandStream stream_hair_file(const std::filesystem::path& path, std::uint64_t chunk_points = std::uint64_t(1) << 20);

// Checks a chunk's values before a writer stores them: InputError naming `path` and the point
// (`floats_before` counts the values handed over before this chunk) when one is NaN or infinite.
void require_finite_points(const std::filesystem::path& path, std::span<const float> xyz, std::uint64_t floats_before);

}  // namespace nf::io
