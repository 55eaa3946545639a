#include "engine/fur/fur_model_file.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::fur {

void save_fur_model(const std::filesystem::path& path, const FurField& field, const StrandPrior& prior, std::uint64_t steps,
                    bool with_decoder) {
  nn::WeightsFile model;
  const RootBox& box = field.box();
  model.config = {{"kind", "fur field"},
                  {"field", field.config().to_json()},
                  {"latent", prior.config().latent},
                  {"box", {{"lo", {box.lo.x, box.lo.y, box.lo.z}}, {"hi", {box.hi.x, box.hi.y, box.hi.z}}}},
                  {"steps", steps},
                  {"train_decoder", with_decoder}};
  std::vector<float> params = field.parameters();
  model.tensors.push_back({"field", {params.size()}, std::move(params)});
  if (!field.length_factors().empty()) {
    std::vector<float> factors = field.length_factors();
    model.tensors.push_back({"length_factors", {factors.size()}, std::move(factors)});
  }
  if (with_decoder) {
    std::vector<float> dec = prior.decoder().parameters().download();
    model.tensors.push_back({"decoder", {dec.size()}, std::move(dec)});
  }
  nn::save_weights(path, model);
}

FurModel load_fur_model(gpu::Context& context, const std::filesystem::path& path) {
  const std::string where = path.string();
  const nn::WeightsFile file = nn::load_weights(path);
  const json& c = file.config;
  const auto fail = [&](const std::string& field, const std::string& what) -> void {
    throw InputError(where + ": config." + field + " " + what + " (is this a fur/model.nfwt?)");
  };
  if (c.value("kind", "") != "fur field") fail("kind", "is not \"fur field\"");
  FurModel m;
  m.prior = shipped_strand_prior(context);
  if (!c.contains("latent") || !c["latent"].is_number_integer() || c["latent"].get<std::int64_t>() != std::int64_t(m.prior->config().latent))
    fail("latent", "does not match the shipped strand prior's latent size " + std::to_string(m.prior->config().latent));
  FurFieldConfig config;
  const json& f = c.value("field", json::object());
  if (!f.contains("frequencies") || !f["frequencies"].is_number_unsigned() || f["frequencies"].get<std::uint64_t>() > 30)
    fail("field.frequencies", "is missing or not an integer in 0..30");
  if (!f.contains("hidden") || !f["hidden"].is_array() || f["hidden"].empty()) fail("field.hidden", "is missing or empty");
  config.frequencies = f["frequencies"].get<std::uint32_t>();
  config.hidden.clear();
  for (const json& h : f["hidden"]) {
    if (!h.is_number_unsigned() || h.get<std::uint64_t>() < 1 || h.get<std::uint64_t>() > 4096) fail("field.hidden", "holds a width outside 1..4096");
    config.hidden.push_back(h.get<std::uint32_t>());
  }
  RootBox box;
  for (auto [name, v] : {std::pair{"lo", &box.lo}, {"hi", &box.hi}}) {
    const json& b = c.value("box", json::object()).value(name, json());
    if (!b.is_array() || b.size() != 3) fail(std::string("box.") + name, "is not 3 numbers");
    for (int a = 0; a < 3; ++a) {
      if (!b[std::size_t(a)].is_number() || !std::isfinite(b[std::size_t(a)].get<double>())) fail(std::string("box.") + name, "holds a value that is not a finite number");
      (*v)[a] = b[std::size_t(a)].get<float>();
    }
  }
  m.steps = c.value("steps", std::uint64_t(0));
  for (const nn::NamedTensor& t : file.tensors)
    if (t.name == "decoder") {
      if (t.values.size() != m.prior->decoder().parameters().size())
        throw InputError(where + ": tensor 'decoder' has " + std::to_string(t.values.size()) + " values, the shipped prior's decoder " +
                         std::to_string(m.prior->decoder().parameters().size()));
      m.prior->decoder().parameters().upload(std::span<const float>(t.values));
    }
  m.field = std::make_unique<FurField>(context, config, *m.prior, box, 1);
  try {
    m.field->set_parameters(file.tensor("field", path).values);
    for (const nn::NamedTensor& t : file.tensors)  // absent in models of earlier versions: all 1
      if (t.name == "length_factors") m.field->set_length_factors(t.values);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what());
  }
  return m;
}

}  // namespace nf::fur
