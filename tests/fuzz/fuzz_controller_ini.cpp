// The one [controller] parser (boardunits) and the board's registers for it: what parses has
// finite coefficients and scale, registers that are 16-bit integers, and writes back to an INI
// that parses to the same controller.
#include "boardunits/controller.hpp"
#include "config/ini.hpp"
#include "fuzz.hpp"

#include <cmath>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  try {
    std::istringstream in(text);
    const mcg::config::Ini ini = mcg::config::Ini::parse(in, "<fuzz>");
    const auto c = mcg::boardunits::controller_from_ini(ini);
    if (!c) return 0;
    const double factor = c->units().factor();
    if (!std::isfinite(factor) || factor == 0.0)
      mcg::fuzz::finding("a controller with a non-finite board scale");
    mcg::config::Ini out;
    mcg::boardunits::controller_to_ini(*c, out);
    std::ostringstream written;
    out.write(written);
    std::istringstream again_in(written.str());
    const auto again = mcg::boardunits::controller_from_ini(mcg::config::Ini::parse(again_in, "<written>"));
    if (!again || again->b != c->b || again->a != c->a)
      mcg::fuzz::finding("controller_to_ini round trip differs");
    try {
      const auto q = mcg::boardunits::board_controller(ini);
      if (q) {
        for (const auto r : q->regs) {
          if (r < -32768 || r > 32767) mcg::fuzz::finding("a register outside 16 bits");
        }
        if (q->coef_frac < 0 || q->coef_frac > 15) mcg::fuzz::finding("coef_frac outside the register");
      }
    } catch (const mcg::Error& e) {
      mcg::fuzz::check_message(e);
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
