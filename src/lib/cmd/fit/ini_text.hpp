// The numbers of mcg-fit's INI results: six significant digits, standard errors as comments.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <string_view>

#include "config/ini.hpp"

namespace mcg::cmd {

/// Six significant digits: what the data supports, and readable in an INI file (never -0).
inline std::string num6(double x) { return fmt::format("{:.6g}", config::without_negative_zero(x)); }

/// "+- SE UNIT", or why there is none.
inline std::string se_comment(double se, std::string_view unit) {
  if (!std::isfinite(se)) return "not determined by the data";
  return unit.empty() ? "+- " + num6(se) : fmt::format("+- {} {}", num6(se), unit);
}

}  // namespace mcg::cmd
