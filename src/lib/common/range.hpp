// Option ranges for CLI11 that refuse NaN and print their bounds as typed.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <sstream>
#include <string>

namespace mcg {

/// CLI::Range(lo, hi) with two differences: NaN is refused ("Value nan is not a number": every
/// comparison with NaN is false, so CLI::Range lets it through, and a NaN option reads as "not
/// given"), and the bounds print as the shortest number (1e-09, not CLI::Range's 0.000000).
/// Infinity passes only where a bound is infinite.
class Range : public CLI::Validator {
 public:
  template <typename T>
  Range(T lo, T hi) : CLI::Validator() {
    std::ostringstream desc;
    desc << CLI::detail::type_name<T>() << " in [" << lo << " - " << hi << "]";
    description(desc.str());
    func_ = [lo, hi](std::string& input) {
      T value{};
      if (!CLI::detail::lexical_cast(input, value)) return "Value " + input + " is not a number";
      if constexpr (std::is_floating_point_v<T>) {
        if (std::isnan(value)) return "Value " + input + " is not a number";
      }
      if (value < lo || value > hi) {
        std::ostringstream out;
        out.precision(10);
        out << "Value " << input << " not in range " << lo << " to " << hi;
        return out.str();
      }
      return std::string();
    };
  }
};

}  // namespace mcg
