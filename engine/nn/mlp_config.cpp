#include "engine/nn/mlp_config.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"

namespace nf::nn {

std::vector<LayerShape> MlpConfig::layers() const {
  std::vector<LayerShape> out;
  std::uint32_t in = input_dim;
  std::uint64_t offset = 0;
  for (std::size_t l = 0; l <= hidden.size(); ++l) {
    LayerShape s;
    s.in = in;
    s.out = l < hidden.size() ? hidden[l] : output_dim;
    s.in_stride = pad4(s.in);
    s.out_stride = pad4(s.out);
    s.weight_offset = (offset + kLayerAlignment - 1) / kLayerAlignment * kLayerAlignment;
    const std::uint64_t weights_end = s.weight_offset + std::uint64_t(s.in_stride) * s.out;
    s.bias_offset = (weights_end + kLayerAlignment - 1) / kLayerAlignment * kLayerAlignment;
    s.activation = l < hidden.size() ? hidden_activation : output_activation;
    offset = s.bias_offset + s.out;
    in = s.out;
    out.push_back(s);
  }
  return out;
}

std::uint64_t MlpConfig::parameter_count() const {
  const auto l = layers();
  return l.back().bias_offset + l.back().out;
}

void MlpConfig::validate() const {
  const auto check_dim = [](std::uint32_t v, const std::string& field) {
    if (v < 1 || v > kMaxWidth)
      throw InputError("mlp " + field + " is " + std::to_string(v) + "; it must be 1.." + std::to_string(kMaxWidth));
  };
  check_dim(input_dim, "input_dim");
  check_dim(output_dim, "output_dim");
  for (std::size_t i = 0; i < hidden.size(); ++i) check_dim(hidden[i], "hidden[" + std::to_string(i) + "]");
  for (const auto* a : {&hidden_activation, &output_activation}) {
    if (a->type == Activation::Softplus && !(std::isfinite(a->beta) && a->beta > 0))
      throw InputError("mlp softplus beta must be positive and finite");
    if (a->type == Activation::Sine && !(std::isfinite(a->omega) && a->omega > 0))
      throw InputError("mlp sine omega must be positive and finite");
  }
}

std::string to_string(Activation a) {
  switch (a) {
    case Activation::None: return "none";
    case Activation::ReLU: return "relu";
    case Activation::Softplus: return "softplus";
    case Activation::Sine: return "sine";
  }
  return "none";
}

Activation activation_from_string(const std::string& name) {
  for (Activation a : {Activation::None, Activation::ReLU, Activation::Softplus, Activation::Sine})
    if (to_string(a) == name) return a;
  throw InputError("unknown activation '" + name + "' (none, relu, softplus, sine)");
}

namespace {
json activation_json(const ActivationSpec& a) {
  return {{"type", to_string(a.type)}, {"beta", a.beta}, {"omega", a.omega}};
}
ActivationSpec activation_spec(const json& j, const std::string& field) {
  if (!j.is_object()) throw InputError("mlp " + field + " must be an object");
  ActivationSpec a;
  a.type = activation_from_string(j.value("type", std::string("none")));
  a.beta = j.value("beta", 100.f);
  a.omega = j.value("omega", 30.f);
  return a;
}
}  // namespace

json to_json(const MlpConfig& c) {
  return {{"input_dim", c.input_dim},
          {"hidden", c.hidden},
          {"output_dim", c.output_dim},
          {"hidden_activation", activation_json(c.hidden_activation)},
          {"output_activation", activation_json(c.output_activation)}};
}

MlpConfig mlp_config_from_json(const json& j) {
  MlpConfig c;
  try {
    c.input_dim = j.at("input_dim").get<std::uint32_t>();
    c.hidden = j.at("hidden").get<std::vector<std::uint32_t>>();
    c.output_dim = j.at("output_dim").get<std::uint32_t>();
  } catch (const json::exception& e) {
    throw InputError(std::string("mlp config: ") + e.what());
  }
  c.hidden_activation = activation_spec(j.value("hidden_activation", json::object()), "hidden_activation");
  c.output_activation = activation_spec(j.value("output_activation", json::object()), "output_activation");
  c.validate();
  return c;
}

}  // namespace nf::nn
