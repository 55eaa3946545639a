#include "engine/fur/fur_view_file.hpp"

#include <cmath>
#include <cstring>

#include "engine/core/atomic_file.hpp"
#include "engine/core/log.hpp"
#include "engine/io/binary_io.hpp"

namespace nf::fur {
namespace {

constexpr char kMagic[8] = {'N', 'F', 'F', 'U', 'R', 'V', 'W', '\0'};
constexpr std::uint32_t kVersion = 1;

template <class T>
void put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof value);
}

void put_crop(std::ostream& out, const io::Camera& c) {
  put(out, c.width), put(out, c.height), put(out, c.fx), put(out, c.fy), put(out, c.cx), put(out, c.cy);
}

void put_floats(std::ostream& out, const std::vector<float>& values) {
  put(out, std::uint64_t(values.size()));
  io::write_array(out, values);
}

// The scene's camera with the stored crop's size and intrinsics (what scaled_crop changes).
io::Camera get_crop(io::ByteReader& in, const io::Camera& camera) {
  io::Camera c = camera;
  c.width = in.value<std::uint32_t>("crop width"), c.height = in.value<std::uint32_t>("crop height");
  c.fx = in.value<double>("crop fx"), c.fy = in.value<double>("crop fy");
  c.cx = in.value<double>("crop cx"), c.cy = in.value<double>("crop cy");
  return c;
}

std::vector<float> get_floats(io::ByteReader& in, std::uint64_t expected, const char* field) {
  const std::uint64_t count = in.value<std::uint64_t>(field);
  if (count != expected) throw InputError(std::string(field) + " has " + std::to_string(count) + " values, not " + std::to_string(expected));
  if (count > in.remaining() / sizeof(float)) throw InputError(std::string(field) + ": the file ends before its " + std::to_string(count) + " values");
  std::vector<float> values(count);
  in.read(values.data(), count, field);
  return values;
}

}  // namespace

void write_fur_view(const std::filesystem::path& file, const FurView& v, const io::Camera* native_crop) {
  write_file_atomic(file, [&](std::ostream& out) {
    out.write(kMagic, sizeof kMagic);
    put(out, kVersion);
    put(out, v.camera);
    put(out, std::uint32_t(v.crop.name.size()));
    out.write(v.crop.name.data(), std::streamsize(v.crop.name.size()));
    put_crop(out, v.crop);
    put(out, v.orientation_reliability), put(out, v.scale);
    for (const std::vector<float>* a : {&v.mask, &v.silhouette_weight, &v.orientation_weight, &v.gabor_angle, &v.gabor_confidence, &v.body_depth, &v.rgb})
      put_floats(out, *a);
    put(out, std::uint8_t(native_crop != nullptr));
    if (native_crop) put_crop(out, *native_crop);
  });
}

std::optional<StoredFurView> read_fur_view(const std::filesystem::path& file, const io::Scene& scene) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return std::nullopt;
  try {
    const std::vector<char> bytes = io::read_file_bytes(file);
    io::ByteReader in(bytes, "the file");
    char magic[sizeof kMagic];
    in.read(magic, sizeof magic, "magic");
    if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) throw InputError("not a fur view file");
    if (const auto version = in.value<std::uint32_t>("version"); version != kVersion)
      throw InputError("format version " + std::to_string(version) + ", this build reads " + std::to_string(kVersion));
    StoredFurView s;
    FurView& v = s.view;
    v.camera = in.value<std::uint32_t>("camera");
    if (v.camera >= scene.cameras.size()) throw InputError("camera " + std::to_string(v.camera) + " is not in the scene");
    const io::Camera& camera = scene.cameras[v.camera];
    const std::uint32_t name_length = in.value<std::uint32_t>("name length");
    if (name_length > in.remaining()) throw InputError("the file ends inside the camera's name");
    std::string name(name_length, '\0');
    in.read(name.data(), name.size(), "name");
    if (name != camera.name) throw InputError("made for camera '" + name + "', not '" + camera.name + "'");
    v.crop = get_crop(in, camera);
    v.orientation_reliability = in.value<double>("reliability"), v.scale = in.value<double>("scale");
    const std::uint64_t n = v.pixels();
    for (auto [a, field] : {std::pair{&v.mask, "mask"}, {&v.silhouette_weight, "silhouette weight"}, {&v.orientation_weight, "orientation weight"},
                            {&v.gabor_angle, "Gabor angle"}, {&v.gabor_confidence, "Gabor confidence"}, {&v.body_depth, "body depth"}})
      *a = get_floats(in, n, field);
    v.rgb = get_floats(in, 3 * n, "rgb");
    if (in.value<std::uint8_t>("native flag")) s.native_crop = get_crop(in, camera);
    if (in.remaining() != 0) throw InputError(std::to_string(in.remaining()) + " bytes after the end");
    // Values a view has: finite intrinsics and scale, a crop of some pixels, a reliability in [0, 1].
    const auto sane = [](const io::Camera& c) {
      return c.width > 0 && c.height > 0 && std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) && std::isfinite(c.cy) && c.fx > 0 && c.fy > 0;
    };
    if (!sane(v.crop) || (s.native_crop && !sane(*s.native_crop)) || !(v.scale > 0 && v.scale <= 1) ||
        !(v.orientation_reliability >= 0 && v.orientation_reliability <= 1))
      throw InputError("a crop, scale or reliability no view has");
    // A crop is a part of the photo: one larger than the photo is of another scene.
    const auto inside = [&](const io::Camera& c, double scale) { return c.width <= std::lround(camera.width * scale) + 1 && c.height <= std::lround(camera.height * scale) + 1; };
    if (!inside(v.crop, v.scale) || (s.native_crop && !inside(*s.native_crop, 1.0)))
      throw InputError("its crop is larger than camera '" + camera.name + "''s photo");
    return s;
  } catch (const InputError& e) {
    log::warn("fur: ", file.string(), " is not read back (", e.what(), "); the view is made anew");
    return std::nullopt;
  }
}

}  // namespace nf::fur
