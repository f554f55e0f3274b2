// load_model: --config files, then --effect texts over them.
#include "model/load.hpp"

#include <algorithm>

#include "config/ini.hpp"

namespace mcg::model {

Model load_model(const config::Ini& ini, const std::vector<std::string>& effects) {
  Model model = model_from_ini(ini);
  for (const auto& text : effects) {
    Effect effect = parse_effect(text, "--effect");
    const auto it = std::find_if(model.effects.begin(), model.effects.end(),
                                 [&](const Effect& e) { return e.name == effect.name; });
    if (it != model.effects.end()) {
      *it = effect;
    } else {
      model.effects.push_back(effect);
    }
  }
  return model;
}

Model load_model(const std::vector<std::string>& configs, const std::vector<std::string>& effects) {
  return load_model(config::Ini::load_all(configs), effects);
}

}  // namespace mcg::model
