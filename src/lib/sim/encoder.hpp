// The board's speed measurement: encoder counts accumulated over a trailing window.
#pragma once

#include "measurement/measurement.hpp"

#include <deque>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mcg::sim {

/// The estimator and its metadata text are owned by the measurement module.
using measurement::CountEstimator;
using measurement::format_rpm_estimator;
using measurement::parse_rpm_estimator;

/// Encoder count of shaft angle theta_rad: floor(theta N / (2 pi)).
double encoder_count(double theta_rad, double counts_per_rev);

/// The estimator fed one sample at a time (t_s increasing), as estimate_rpm() computes it over a
/// whole record: push() returns the rpm at the sample. It keeps only the samples of the last
/// window, so its memory does not grow with the run.
class StreamingRpmEstimator {
 public:
  explicit StreamingRpmEstimator(const CountEstimator& estimator);
  double push(double t_s, double theta_rad);

 private:
  CountEstimator m_e;
  double m_tol;
  bool m_started = false;
  double m_t0_s = 0.0;
  double m_theta0_rad = 0.0;
  std::deque<std::pair<double, double>> m_hist;   ///< (t, theta) from the last one at or before t - W
};

/// The estimator applied to a shaft angle sampled at increasing times t_s (the shaft at rest
/// at theta_rad[0] before t_s[0]); the angle at t - W between samples is interpolated linearly.
std::vector<double> estimate_rpm(const std::vector<double>& t_s, const std::vector<double>& theta_rad,
                                 const CountEstimator& estimator);

}  // namespace mcg::sim
