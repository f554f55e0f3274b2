// The measurement metadata grammar (see measurement.hpp).
#include "measurement/measurement.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/error.hpp"
#include "common/text.hpp"
#include "config/ini.hpp"
#include "table/table.hpp"

namespace mcg::measurement {

namespace {

/// Splits off the next blank-separated word of `s`.
std::string_view next_word(std::string_view& s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == ',')) s.remove_prefix(1);
  std::size_t n = 0;
  while (n < s.size() && s[n] != ' ' && s[n] != '\t' && s[n] != ',') ++n;
  const std::string_view word = s.substr(0, n);
  s.remove_prefix(n);
  return word;
}

/// The clauses of `text`: split at commas outside parentheses.
std::vector<std::string_view> clauses(std::string_view text) {
  std::vector<std::string_view> out;
  int depth = 0;
  std::size_t begin = 0;
  for (std::size_t k = 0; k <= text.size(); ++k) {
    if (k < text.size() && text[k] == '(') ++depth;
    if (k < text.size() && text[k] == ')') --depth;
    if (k == text.size() || (text[k] == ',' && depth == 0)) {
      out.push_back(trim(text.substr(begin, k - begin)));
      begin = k + 1;
    }
  }
  return out;
}

/// Strips `prefix` from `s`; false when `s` does not start with it.
bool eat(std::string_view& s, std::string_view prefix) {
  if (s.substr(0, prefix.size()) != prefix) return false;
  s.remove_prefix(prefix.size());
  return true;
}

/// Reads a number up to (not including) `stop`, which must follow it.
bool number_until(std::string_view& s, std::string_view stop, double& value) {
  const auto at = s.find(stop);
  if (at == std::string_view::npos || !table::parse_number(trim(s.substr(0, at)), value)) return false;
  s.remove_prefix(at + stop.size());
  return true;
}

std::string num(double v) { return config::format_number(v); }

}  // namespace

CountEstimator parse_rpm_estimator(std::string_view text, std::string_view where) {
  std::string_view s = text;
  CountEstimator e;
  const auto bad = [&]() {
    fail("{}: expected 'counts over <W> s window, <N> counts/rev', got {}", where, quote(text));
  };
  if (next_word(s) != "counts" || next_word(s) != "over") bad();
  if (!table::parse_number(next_word(s), e.window_s)) bad();
  if (next_word(s) != "s" || next_word(s) != "window") bad();
  if (!table::parse_number(next_word(s), e.counts_per_rev)) bad();
  if (next_word(s) != "counts/rev" || !next_word(s).empty()) bad();
  if (!(e.window_s > 0.0) || !std::isfinite(e.window_s)) fail("{}: window must be > 0 s in {}", where, quote(text));
  if (!(e.counts_per_rev >= 1.0) || !std::isfinite(e.counts_per_rev)) {
    fail("{}: counts/rev must be >= 1 in {}", where, quote(text));
  }
  return e;
}

std::string format_rpm_estimator(const CountEstimator& e) {
  return "counts over " + num(e.window_s) + " s window, " + num(e.counts_per_rev) + " counts/rev";
}

double CurrentChain::step_A() const {
  if (!std::isfinite(adc_bits) || !std::isfinite(adc_low_V) || !std::isfinite(adc_high_V)) return k_nan;
  const double shunt = std::isfinite(shunt_ohm) ? shunt_ohm : 1.0;
  return (adc_high_V - adc_low_V) / std::pow(2.0, adc_bits) / shunt;
}

bool CurrentChain::at_rail(double i_A) const {
  if (!std::isfinite(range_low_A) && !std::isfinite(range_high_A)) return false;
  const double step = step_A();
  const double margin = std::isfinite(step) ? 0.1 * step : 1e-6;
  return i_A >= range_high_A - margin || i_A <= range_low_A + margin;
}

double CurrentChain::quantise(double i_A) const {
  const double step = step_A();
  if (!std::isfinite(step)) fail("i_measurement: no ADC bits and span to quantise with");
  const double shunt = std::isfinite(shunt_ohm) ? shunt_ohm : 1.0;
  const double offset = std::isfinite(offset_V) ? offset_V : 0.0;
  const double codes = std::pow(2.0, adc_bits);
  const double span = adc_high_V - adc_low_V;
  const double code = std::clamp(std::round((i_A * shunt + offset - adc_low_V) / span * codes), 0.0, codes - 1.0);
  return (adc_low_V + code * span / codes - offset) / shunt;
}

CurrentChain board_current_chain() {
  CurrentChain c;
  c.shunt_ohm = 1.0;
  c.adc_bits = 10.0;
  c.adc_low_V = 0.0;
  c.adc_high_V = 5.0;
  c.offset_V = 2.5;
  c.range_low_A = -2.5;
  c.range_high_A = 2.495;
  c.saturates = true;
  return c;
}

CurrentChain parse_i_measurement(std::string_view text, std::string_view where) {
  CurrentChain c;
  bool seen_shunt = false;
  bool seen_adc = false;
  bool seen_sigma = false;
  const auto bad = [&](std::string_view clause, std::string_view expected) {
    fail("{}: clause {} of {}: expected {}", where, quote(clause), quote(text), expected);
  };
  const auto once = [&](bool& seen, std::string_view clause) {
    if (seen) bad(clause, "each clause at most once");
    seen = true;
  };
  for (std::string_view clause : clauses(text)) {
    std::string_view s = clause;
    if (clause.empty()) bad(clause, "a clause between the commas");
    if (clause == "simulated") {
      c.simulated = true;
    } else if (clause.ends_with(" ohm shunt")) {
      once(seen_shunt, clause);
      if (!table::parse_number(trim(clause.substr(0, clause.size() - 10)), c.shunt_ohm) || !(c.shunt_ohm > 0.0)) {
        bad(clause, "'<R> ohm shunt' with R > 0");
      }
    } else if (clause.find("-bit ADC") != std::string_view::npos) {
      once(seen_adc, clause);
      const std::string_view form = "'<B>-bit ADC [over <lo>-<hi> V] [with <o> V mid-scale offset] "
                                    "[(range <a>..<b> A[, saturates])]'";
      if (!number_until(s, "-bit ADC", c.adc_bits) || !(c.adc_bits >= 1.0 && c.adc_bits <= 32.0)) bad(clause, form);
      s = trim(s);
      if (eat(s, "over ")) {
        // "<lo>-<hi> V": the dash after the first character separates (lo may be negative).
        const auto dash = s.find('-', 1);
        if (dash == std::string_view::npos || !table::parse_number(trim(s.substr(0, dash)), c.adc_low_V)) bad(clause, form);
        s.remove_prefix(dash + 1);
        if (!number_until(s, " V", c.adc_high_V) || !(c.adc_low_V < c.adc_high_V)) bad(clause, form);
        s = trim(s);
      }
      if (eat(s, "with ")) {
        if (!number_until(s, " V mid-scale offset", c.offset_V)) bad(clause, form);
        s = trim(s);
      }
      if (eat(s, "(range ")) {
        if (!number_until(s, "..", c.range_low_A) || !number_until(s, " A", c.range_high_A) ||
            !(c.range_low_A < c.range_high_A)) {
          bad(clause, form);
        }
        s = trim(s);
        if (eat(s, ",")) {
          s = trim(s);
          if (!eat(s, "saturates")) bad(clause, form);
          c.saturates = true;
        }
        if (!eat(s, ")")) bad(clause, form);
      }
      if (!trim(s).empty()) bad(clause, form);
    } else if (eat(s, "noise sigma ") || (eat(s, "nominal ") && eat(s, "noise sigma "))) {
      once(seen_sigma, clause);
      if (!number_until(s, " A", c.sigma_A) || !trim(s).empty() || !(c.sigma_A >= 0.0)) {
        bad(clause, "'[nominal ]noise sigma <s> A' with s >= 0");
      }
    } else {
      bad(clause, "'<R> ohm shunt', '<B>-bit ADC ...', 'noise sigma <s> A' or 'simulated'");
    }
  }
  return c;
}

std::string format_i_measurement(const CurrentChain& c) {
  std::vector<std::string> parts;
  if (std::isfinite(c.shunt_ohm)) parts.push_back(num(c.shunt_ohm) + " ohm shunt");
  if (std::isfinite(c.adc_bits)) {
    std::string adc = num(c.adc_bits) + "-bit ADC";
    if (std::isfinite(c.adc_low_V)) adc += " over " + num(c.adc_low_V) + "-" + num(c.adc_high_V) + " V";
    if (std::isfinite(c.offset_V)) adc += " with " + num(c.offset_V) + " V mid-scale offset";
    if (std::isfinite(c.range_low_A)) {
      adc += " (range " + num(c.range_low_A) + ".." + num(c.range_high_A) + " A" + (c.saturates ? ", saturates)" : ")");
    }
    parts.push_back(adc);
  }
  if (c.simulated) parts.emplace_back("simulated");
  if (std::isfinite(c.sigma_A)) parts.push_back("noise sigma " + num(c.sigma_A) + " A");
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}

}  // namespace mcg::measurement
