// Encoder count estimator shared by mcg-sim and the gap diagnosis.
#include "sim/encoder.hpp"

#include "common/demand.hpp"
#include <cmath>
#include <numbers>

namespace mcg::sim {

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
  MCG_DEMAND(t.size() == theta.size());
  std::vector<double> rpm(t.size(), 0.0);
  StreamingRpmEstimator estimator(e);
  for (std::size_t k = 0; k < t.size(); ++k) rpm[k] = estimator.push(t[k], theta[k]);
  return rpm;
}

}  // namespace mcg::sim
