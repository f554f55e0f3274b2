// The model a tool runs: its INI files and --effect texts, merged in one place.
#pragma once

#include <string>
#include <vector>

#include "model/model.hpp"

namespace mcg::config {
class Ini;
}

namespace mcg::model {

/// model_from_ini(ini) with the catalog effects `effects` ("NAME[:key=value,...]", named
/// "--effect" in errors) added; each replaces an effect of its name that `ini` configures.
Model load_model(const config::Ini& ini, const std::vector<std::string>& effects);

/// The same on the INI files `configs` (later files win).
Model load_model(const std::vector<std::string>& configs, const std::vector<std::string>& effects);

}  // namespace mcg::model
