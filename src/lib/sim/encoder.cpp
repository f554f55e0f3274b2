// Encoder count estimator shared by mcg-sim and the gap diagnosis.
#include "sim/encoder.hpp"

#include <cassert>
#include <charconv>
#include <cmath>
#include <numbers>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "table/table.hpp"

namespace mcg::sim {

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

}  // namespace

CountEstimator parse_rpm_estimator(std::string_view text, std::string_view where) {
  // Grammar: "counts over <W> s window, <N> counts/rev" (blanks and the comma are free).
  std::string_view s = text;
  CountEstimator e;
  const auto bad = [&]() {
    fail("{}: expected 'counts over <W> s window, <N> counts/rev', got '{}'", where, text);
  };
  if (next_word(s) != "counts" || next_word(s) != "over") bad();
  if (!table::parse_number(next_word(s), e.window_s)) bad();
  if (next_word(s) != "s" || next_word(s) != "window") bad();
  if (!table::parse_number(next_word(s), e.counts_per_rev)) bad();
  if (next_word(s) != "counts/rev" || !next_word(s).empty()) bad();
  if (!(e.window_s > 0.0) || !std::isfinite(e.window_s)) fail("{}: window must be > 0 s in '{}'", where, text);
  if (!(e.counts_per_rev >= 1.0) || !std::isfinite(e.counts_per_rev)) {
    fail("{}: counts/rev must be >= 1 in '{}'", where, text);
  }
  return e;
}

std::string format_rpm_estimator(const CountEstimator& e) {
  return "counts over " + config::format_number(e.window_s) + " s window, " +
         config::format_number(e.counts_per_rev) + " counts/rev";
}

double encoder_count(double theta_rad, double counts_per_rev) {
  return std::floor(theta_rad * counts_per_rev / (2.0 * std::numbers::pi));
}

std::vector<double> estimate_rpm(const std::vector<double>& t, const std::vector<double>& theta,
                                 const CountEstimator& e) {
  assert(t.size() == theta.size());
  const std::size_t n = t.size();
  std::vector<double> rpm(n, 0.0);
  if (n == 0) return rpm;
  // Sample times within this tolerance of t - W count as the same instant (logs print
  // times rounded to the microsecond).
  const double tol = 1e-9 + 1e-6 * e.window_s;
  const double scale = e.rpm_per_count();
  std::size_t j = 0;  // last sample with t[j] <= t - W + tol
  for (std::size_t k = 0; k < n; ++k) {
    const double t_back = t[k] - e.window_s;
    while (j + 1 < n && t[j + 1] <= t_back + tol) ++j;
    double theta_back = theta[0];
    if (t_back > t[0] + tol) {
      if (std::abs(t[j] - t_back) <= tol || j + 1 >= n) {
        theta_back = theta[j];
      } else {
        const double f = (t_back - t[j]) / (t[j + 1] - t[j]);
        theta_back = theta[j] + f * (theta[j + 1] - theta[j]);
      }
    } else if (std::abs(t_back - t[0]) <= tol) {
      theta_back = theta[0];
    }
    rpm[k] = (encoder_count(theta[k], e.counts_per_rev) - encoder_count(theta_back, e.counts_per_rev)) * scale;
  }
  return rpm;
}

}  // namespace mcg::sim
