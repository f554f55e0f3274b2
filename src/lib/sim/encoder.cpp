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

StreamingRpmEstimator::StreamingRpmEstimator(const CountEstimator& estimator)
    // Sample times within this tolerance of t - W count as the same instant (logs print
    // times rounded to the microsecond).
    : m_e(estimator), m_tol(1e-9 + 1e-6 * estimator.window_s) {}

double StreamingRpmEstimator::push(double t_s, double theta_rad) {
  if (!m_started) {
    m_started = true;
    m_t0_s = t_s;
    m_theta0_rad = theta_rad;
  }
  m_hist.emplace_back(t_s, theta_rad);
  const double t_back = t_s - m_e.window_s;
  while (m_hist.size() > 1 && m_hist[1].first <= t_back + m_tol) m_hist.pop_front();
  double theta_back = m_theta0_rad;
  if (t_back > m_t0_s + m_tol) {
    const auto& [tj, thj] = m_hist.front();
    if (std::abs(tj - t_back) <= m_tol || m_hist.size() < 2) {
      theta_back = thj;
    } else {
      const auto& [tk, thk] = m_hist[1];
      theta_back = thj + (t_back - tj) / (tk - tj) * (thk - thj);
    }
  }
  return (encoder_count(theta_rad, m_e.counts_per_rev) - encoder_count(theta_back, m_e.counts_per_rev)) *
         m_e.rpm_per_count();
}

std::vector<double> estimate_rpm(const std::vector<double>& t, const std::vector<double>& theta,
                                 const CountEstimator& e) {
  assert(t.size() == theta.size());
  std::vector<double> rpm(t.size(), 0.0);
  StreamingRpmEstimator estimator(e);
  for (std::size_t k = 0; k < t.size(); ++k) rpm[k] = estimator.push(t[k], theta[k]);
  return rpm;
}

}  // namespace mcg::sim
