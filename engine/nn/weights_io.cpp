#include "engine/nn/weights_io.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"

namespace nf::nn {
namespace {

constexpr char kMagic[4] = {'N', 'F', 'W', 'T'};

void put_u32(std::ostream& out, std::uint32_t v) {
  const unsigned char b[4] = {std::uint8_t(v), std::uint8_t(v >> 8), std::uint8_t(v >> 16), std::uint8_t(v >> 24)};
  out.write(reinterpret_cast<const char*>(b), 4);
}

std::uint32_t get_u32(const unsigned char* b) {
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

std::uint64_t element_count(const std::vector<std::uint64_t>& shape) {
  std::uint64_t n = 1;
  for (auto d : shape) n *= d;
  return n;
}

std::string shape_text(const std::vector<std::uint64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

}  // namespace

const NamedTensor& WeightsFile::tensor(const std::string& name, const std::filesystem::path& source) const {
  for (const auto& t : tensors)
    if (t.name == name) return t;
  throw InputError(source.string() + ": tensor '" + name + "' is missing");
}

void save_weights(const std::filesystem::path& path, const WeightsFile& w) {
  json header{{"config", w.config}, {"tensors", json::array()}};
  std::uint64_t offset = 0;
  for (const auto& t : w.tensors) {
    if (element_count(t.shape) != t.values.size())
      throw InternalError("weights: tensor '" + t.name + "' has " + std::to_string(t.values.size()) +
                          " values for shape " + shape_text(t.shape));
    header["tensors"].push_back({{"name", t.name}, {"shape", t.shape}, {"offset", offset}, {"count", t.values.size()}});
    offset += t.values.size() * 4;
  }
  const std::string text = header.dump();
  write_file_atomic(path, [&](std::ostream& out) {
    out.write(kMagic, 4);
    put_u32(out, kWeightsVersion);
    put_u32(out, std::uint32_t(text.size()));
    out.write(text.data(), std::streamsize(text.size()));
    for (const auto& t : w.tensors)
      for (float v : t.values) put_u32(out, std::bit_cast<std::uint32_t>(v));  // little-endian on any host
  });
}

WeightsFile load_weights(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open weights file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_weights(bytes, path.string());
}

WeightsFile parse_weights(std::string_view text, const std::string& where) {
  const std::span<const unsigned char> bytes(reinterpret_cast<const unsigned char*>(text.data()), text.size());
  if (bytes.size() < 12 || std::memcmp(bytes.data(), kMagic, 4) != 0)
    throw InputError(where + ": not an nf_gpu weights file (magic 'NFWT' missing)");
  const std::uint32_t version = get_u32(&bytes[4]);
  if (version != kWeightsVersion)
    throw InputError(where + ": weights format version " + std::to_string(version) + ", this build reads " +
                     std::to_string(kWeightsVersion));
  const std::uint64_t header_length = get_u32(&bytes[8]);
  if (12 + header_length > bytes.size())
    throw InputError(where + ": header length " + std::to_string(header_length) + " runs past the end of the file");
  json header;
  try {
    header = json::parse(bytes.begin() + 12, bytes.begin() + std::ptrdiff_t(12 + header_length));
  } catch (const json::exception& e) {
    throw InputError(where + ": header is not valid JSON (" + e.what() + ")");
  }
  if (!header.contains("tensors") || !header["tensors"].is_array())
    throw InputError(where + ": header field 'tensors' is missing or not a list");
  WeightsFile w;
  w.config = header.value("config", json::object());
  const std::uint64_t data_start = 12 + header_length, data_size = bytes.size() - data_start;
  for (const auto& entry : header["tensors"]) {
    NamedTensor t;
    try {
      t.name = entry.at("name").get<std::string>();
      // Sizes and offsets are whole numbers >= 0: json's own conversion turns 4e30 or -1 into garbage.
      const auto whole = [&](const json& v, const char* field) {
        if (!v.is_number_unsigned())
          throw InputError(where + ": tensor '" + t.name + "' " + field + " " + v.dump() + " is not a whole number >= 0");
        return v.get<std::uint64_t>();
      };
      const json& shape = entry.at("shape");
      if (!shape.is_array()) throw InputError(where + ": tensor '" + t.name + "' shape is not a list");
      for (const json& d : shape) t.shape.push_back(whole(d, "shape"));
      const std::uint64_t offset = whole(entry.at("offset"), "offset");
      const std::uint64_t count = whole(entry.at("count"), "count");
      if (count != element_count(t.shape))
        throw InputError(where + ": tensor '" + t.name + "' has count " + std::to_string(count) + " but shape " +
                         shape_text(t.shape));
      if (offset % 4 || offset > data_size || count > (data_size - offset) / 4)
        throw InputError(where + ": tensor '" + t.name + "' (offset " + std::to_string(offset) + ", " +
                         std::to_string(count) + " floats) runs past the end of the file (truncated?)");
      t.values.resize(count);
      for (std::uint64_t i = 0; i < count; ++i) {
        const float v = std::bit_cast<float>(get_u32(&bytes[data_start + offset + 4 * i]));
        if (!std::isfinite(v))
          throw InputError(where + ": tensor '" + t.name + "' element " + std::to_string(i) + " is not finite");
        t.values[i] = v;
      }
    } catch (const json::exception& e) {
      throw InputError(where + ": a tensor entry is malformed (" + e.what() + ")");
    }
    w.tensors.push_back(std::move(t));
  }
  return w;
}

WeightsFile mlp_weights(const MlpConfig& config, std::span<const float> parameters) {
  if (parameters.size() != config.parameter_count())
    throw InternalError("mlp_weights: parameter count does not match the configuration");
  WeightsFile w;
  w.config = {{"kind", "mlp"}, {"mlp", to_json(config)}};
  const auto layers = config.layers();
  for (std::size_t li = 0; li < layers.size(); ++li) {
    const LayerShape& l = layers[li];
    NamedTensor weight{"layer" + std::to_string(li) + ".weight", {l.out, l.in}, {}};
    for (std::uint32_t o = 0; o < l.out; ++o)
      for (std::uint32_t k = 0; k < l.in; ++k) weight.values.push_back(parameters[l.weight_offset + std::uint64_t(o) * l.in_stride + k]);
    NamedTensor bias{"layer" + std::to_string(li) + ".bias", {l.out}, {}};
    for (std::uint32_t o = 0; o < l.out; ++o) bias.values.push_back(parameters[l.bias_offset + o]);
    w.tensors.push_back(std::move(weight));
    w.tensors.push_back(std::move(bias));
  }
  return w;
}

std::vector<float> mlp_parameters(const MlpConfig& expected, const WeightsFile& w, const std::filesystem::path& source) {
  const std::string where = source.string();
  if (!w.config.contains("mlp")) throw InputError(where + ": config has no 'mlp' section");
  const MlpConfig found = mlp_config_from_json(w.config["mlp"]);
  if (to_json(found) != to_json(expected))
    throw InputError(where + ": network configuration " + to_json(found).dump() + " does not match the expected " +
                     to_json(expected).dump());
  std::vector<float> p(expected.parameter_count(), 0.f);
  const auto layers = expected.layers();
  for (std::size_t li = 0; li < layers.size(); ++li) {
    const LayerShape& l = layers[li];
    const NamedTensor& weight = w.tensor("layer" + std::to_string(li) + ".weight", source);
    const NamedTensor& bias = w.tensor("layer" + std::to_string(li) + ".bias", source);
    if (weight.shape != std::vector<std::uint64_t>{l.out, l.in})
      throw InputError(where + ": tensor '" + weight.name + "' has shape " + shape_text(weight.shape) + ", expected [" +
                       std::to_string(l.out) + ", " + std::to_string(l.in) + "]");
    if (bias.shape != std::vector<std::uint64_t>{l.out})
      throw InputError(where + ": tensor '" + bias.name + "' has shape " + shape_text(bias.shape) + ", expected [" +
                       std::to_string(l.out) + "]");
    for (std::uint32_t o = 0; o < l.out; ++o) {
      for (std::uint32_t k = 0; k < l.in; ++k) p[l.weight_offset + std::uint64_t(o) * l.in_stride + k] = weight.values[std::size_t(o) * l.in + k];
      p[l.bias_offset + o] = bias.values[o];
    }
  }
  return p;
}

}  // namespace nf::nn
