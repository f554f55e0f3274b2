// The measurement metadata grammar (see measurement.hpp).
#include "measurement/measurement.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/demand.hpp"
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

double parse_gear_ratio(std::string_view text, std::string_view where) {
  double ratio = 0.0;
  if (!table::parse_number(trim(text), ratio) || !std::isfinite(ratio) || !(ratio > 0.0)) {
    fail("{}: expected a gear ratio > 0 (motor turns per turn of the measured shaft), got {}", where,
         quote(text));
  }
  return ratio;
}

std::string format_gear_ratio(double ratio) { return num(ratio); }

SpeedFilter parse_speed_filter(std::string_view text, std::string_view where) {
  std::string_view s = trim(text);
  SpeedFilter f;
  const auto positive = [&](double v) { return std::isfinite(v) && v > 0.0; };
  if (s == "none") return f;
  if (eat(s, "first-order low-pass, time constant ")) {
    f.kind = SpeedFilter::Kind::low_pass;
    if (number_until(s, " s", f.time_constant_s) && s.empty() && positive(f.time_constant_s)) return f;
  } else if (eat(s, "moving average over ")) {
    f.kind = SpeedFilter::Kind::moving_average;
    if (number_until(s, " s", f.window_s) && s.empty() && positive(f.window_s)) return f;
  }
  fail(
      "{}: expected 'first-order low-pass, time constant <tau> s', 'moving average over <W> s' or "
      "'none' (tau, W > 0), got {}",
      where, quote(text));
}

std::string format_speed_filter(const SpeedFilter& f) {
  switch (f.kind) {
    case SpeedFilter::Kind::low_pass:
      return "first-order low-pass, time constant " + num(f.time_constant_s) + " s";
    case SpeedFilter::Kind::moving_average:
      return "moving average over " + num(f.window_s) + " s";
    case SpeedFilter::Kind::none:
      break;
  }
  return "none";
}

double SpeedFilterStream::push(double t_s, double x) {
  if (!std::isfinite(x) || m_filter.kind == SpeedFilter::Kind::none) return x;
  if (m_filter.kind == SpeedFilter::Kind::low_pass) {
    if (!std::isfinite(m_state)) {
      m_state = x;
    } else {
      const double a = std::exp(-(t_s - m_t_prev) / m_filter.time_constant_s);
      m_state = a * m_state + (1.0 - a) * x;
    }
    m_t_prev = t_s;
    return m_state;
  }
  // Moving average: the mean of the samples with t in (t_s - W, t_s].
  m_window.emplace_back(t_s, x);
  m_sum += x;
  for (; m_window[m_first].first <= t_s - m_filter.window_s; ++m_first) m_sum -= m_window[m_first].second;
  if (m_first > 4096 && 2 * m_first > m_window.size()) {  // drop what left the window
    m_window.erase(m_window.begin(), m_window.begin() + static_cast<std::ptrdiff_t>(m_first));
    m_first = 0;
  }
  return m_sum / static_cast<double>(m_window.size() - m_first);
}

std::vector<double> SpeedFilter::apply(const std::vector<double>& t_s, const std::vector<double>& x) const {
  MCG_DEMAND(t_s.size() == x.size());
  SpeedFilterStream stream(*this);
  std::vector<double> y(x.size());
  for (std::size_t n = 0; n < x.size(); ++n) y[n] = stream.push(t_s[n], x[n]);
  return y;
}

double settle_gear_ratio(std::optional<double> stated, std::optional<double> ini,
                         std::optional<double> override, std::string_view source) {
  if (override) return *override;
  if (stated && ini && *stated != *ini) {
    fail(
        "{}: gear_ratio {} differs from the model's [measurement] gear_ratio {} (give --gear-ratio to "
        "choose)",
        source, format_gear_ratio(*stated), format_gear_ratio(*ini));
  }
  return stated.value_or(ini.value_or(1.0));
}

SpeedPath settle_speed_path(const SpeedPath& stated, const SpeedPath& ini,
                            std::optional<double> gear_override, std::string_view source) {
  if (stated.filter && ini.filter &&
      format_speed_filter(*stated.filter) != format_speed_filter(*ini.filter)) {
    fail("{}: speed_filter {} differs from the model's [measurement] speed_filter {}", source,
         quote(format_speed_filter(*stated.filter)), quote(format_speed_filter(*ini.filter)));
  }
  SpeedPath settled;
  settled.gear_ratio = settle_gear_ratio(stated.gear_ratio, ini.gear_ratio, gear_override, source);
  settled.filter = stated.filter.value_or(ini.filter.value_or(SpeedFilter{}));
  return settled;
}

SpeedPath speed_path_stated(std::optional<std::string> gear_ratio, std::optional<std::string> speed_filter,
                            std::string_view source) {
  SpeedPath stated;
  if (gear_ratio) stated.gear_ratio = parse_gear_ratio(*gear_ratio, fmt::format("{}: gear_ratio", source));
  if (speed_filter)
    stated.filter = parse_speed_filter(*speed_filter, fmt::format("{}: speed_filter", source));
  return stated;
}

SpeedPath speed_path_from_ini(const config::Ini& ini) {
  SpeedPath path;
  constexpr std::string_view sec = "measurement";
  for (const auto* entry : ini.entries(sec)) {
    const std::string where =
        fmt::format("{}: [{}] {}", entry->origin.empty() ? "config" : entry->origin, sec, entry->key);
    if (entry->key == "gear_ratio") {
      path.gear_ratio = parse_gear_ratio(entry->value, where);
    } else if (entry->key == "speed_filter") {
      path.filter = parse_speed_filter(entry->value, where);
    } else {
      ini.reject(sec, entry->key, "unknown key (gear_ratio, speed_filter)");
    }
  }
  return path;
}

void speed_path_to_ini(const SpeedPath& path, config::Ini& ini) {
  if (path.gear_ratio) {
    ini.set("measurement", "gear_ratio", format_gear_ratio(*path.gear_ratio),
            "motor turns per turn of the shaft whose speed is measured");
  }
  if (path.filter) ini.set("measurement", "speed_filter", format_speed_filter(*path.filter));
}

}  // namespace mcg::measurement
