// The INI reader, the model's parameter sets and the effect catalog: what parses must write
// back and parse again to the same parameters.
#include "config/ini.hpp"
#include "fuzz.hpp"
#include "model/model.hpp"

#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  try {
    const std::string first_line = text.substr(0, text.find('\n'));
    (void)mcg::model::parse_effect(first_line);
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  try {
    std::istringstream in(text);
    const mcg::config::Ini ini = mcg::config::Ini::parse(in, "<fuzz>");
    const mcg::model::Model m = mcg::model::model_from_ini(ini);
    mcg::config::Ini out;
    mcg::model::model_to_ini(m, out);
    std::ostringstream written;
    out.write(written);
    std::istringstream again_in(written.str());
    const mcg::model::Model again = mcg::model::model_from_ini(mcg::config::Ini::parse(again_in, "<written>"));
    const auto a = mcg::model::parameters(m);
    const auto b = mcg::model::parameters(again);
    if (a.size() != b.size()) mcg::fuzz::finding("model_to_ini round trip changes the parameter set");
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
