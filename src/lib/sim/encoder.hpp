// The board's speed measurement: encoder counts accumulated over a trailing window.
#pragma once

#include <deque>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mcg::sim {

/// "counts over W s window, N counts/rev": the count is floor(theta N / (2 pi)) as a real
/// up/down counter holds it, and rpm(t) = (count(t) - count(t - W)) / N / W * 60.
struct CountEstimator {
  double window_s = 0.005;
  double counts_per_rev = 2048.0;   ///< 512-line encoder, x4 quadrature decoding

  /// Speed resolution, rpm per count: 60 / (N W).
  double rpm_per_count() const { return 60.0 / (counts_per_rev * window_s); }
};

/// Parses the data contract's `rpm_estimator` text, e.g. "counts over 0.005 s window,
/// 2048 counts/rev". Throws mcg::Error "<where>: ..." when it does not match.
CountEstimator parse_rpm_estimator(std::string_view text, std::string_view where = "rpm_estimator");
/// The metadata text for `estimator`, in the form parse_rpm_estimator() reads.
std::string format_rpm_estimator(const CountEstimator& estimator);

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
