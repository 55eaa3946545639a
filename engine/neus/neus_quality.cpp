#include "engine/neus/neus_quality.hpp"

#include "engine/core/error.hpp"

namespace nf::neus {

NeusQuality quality_preset(const std::string& name) {
  NeusQuality q;
  q.name = name;
  if (name == "draft") {
    q.field.hash = {16, 2, 17, 16, 1024};
    q.field.sdf_hidden = {64};
    q.field.colour_hidden = {64};
    q.training.steps = 1200;
    q.training.rays = 512;
    q.training.samples_per_ray = 32;
    q.mesh_resolution = 192;
  } else if (name == "default") {
    q.field.hash = {16, 2, 19, 16, 2048};
    q.field.sdf_hidden = {64};
    q.field.colour_hidden = {64, 64};
    q.training.steps = 5000;
    q.training.rays = 2048;
    q.training.samples_per_ray = 48;
    q.mesh_resolution = 256;
  } else if (name == "paper") {
    q.field.encoding = FieldEncoding::Frequency;
    q.field.frequency = {3, 6, true};
    q.field.sdf_hidden = std::vector<std::uint32_t>(8, 256);
    q.field.features = 256;
    q.field.colour_hidden = std::vector<std::uint32_t>(4, 256);
    q.training.steps = 300000;
    q.training.rays = 512;
    q.training.samples_per_ray = 128;
    q.training.lr = 5e-4f;
    q.training.warmup = 5000;
    q.training.lr_floor = 0.05f;
    q.mesh_resolution = 512;
  } else {
    throw InputError("unknown quality '" + name + "': use draft, default or paper");
  }
  return q;
}

}  // namespace nf::neus
