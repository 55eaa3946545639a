#pragma once
// Network weights on disk: a versioned little-endian format with shapes and configuration.
//
//   bytes 0-3   magic "NFWT"
//   bytes 4-7   uint32 format version (1)
//   bytes 8-11  uint32 header length H
//   H bytes     JSON: {"config": {...}, "tensors": [{"name", "shape": [...], "offset", "count"}]}
//   then        float32 little-endian data; each tensor at `offset` bytes past the header
//
// Files are written atomically. Loading checks every field, every shape and every size against the
// file's length, and names the file and the field or tensor that is wrong.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

constexpr std::uint32_t kWeightsVersion = 1;

struct NamedTensor {
  std::string name;
  std::vector<std::uint64_t> shape;
  std::vector<float> values;  // product of shape
};

struct WeightsFile {
  json config;
  std::vector<NamedTensor> tensors;
  const NamedTensor& tensor(const std::string& name, const std::filesystem::path& source) const;
};

void save_weights(const std::filesystem::path& path, const WeightsFile& weights);
WeightsFile load_weights(const std::filesystem::path& path);
// The same from the bytes of such a file (e.g. embedded in the binary); `source` names it in errors.
WeightsFile parse_weights(std::string_view bytes, const std::string& source);

// An MLP's parameters as tensors "layer<i>.weight" [out, in] and "layer<i>.bias" [out] (no padding),
// and back into the Mlp layout, checking the file's network configuration and every shape.
WeightsFile mlp_weights(const MlpConfig& config, std::span<const float> parameters);
std::vector<float> mlp_parameters(const MlpConfig& expected, const WeightsFile& weights,
                                  const std::filesystem::path& source);

}  // namespace nf::nn
