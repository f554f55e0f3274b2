// Time-domain transfer-function fit: the exact sampled simulation against closed forms, and round
// trips (simulate a known plant, fit it back) with and without noise; what a run must hold.
#include "fit/tf.hpp"

#include "signal/excitation.hpp"
#include "table/table.hpp"
#include "test_support_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace mcg::fit {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

RationalTf report_plant() {
  // 16.557/((s/65+1)*(s/950+1)) in descending powers.
  return {{16.557}, {1.0 / (65.0 * 950.0), 1.0 / 65.0 + 1.0 / 950.0, 1.0}};
}

table::Table run_table(const std::vector<double>& u, const std::vector<double>& y, double dt_s) {
  table::Table t;
  t.source = "run.csv";
  t.names = {"t", "v", "rpm"};
  std::vector<double> time(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) time[k] = static_cast<double>(k) * dt_s;
  t.columns = {time, u, y};
  t.first_line = 4;
  return t;
}

/// A PRBS about `bias` (V), one bit per `clock` samples, seeded.
std::vector<double> prbs(std::size_t samples, double bias, double amp, std::size_t clock,
                         std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<double> u = signal::prbs_signal(samples, amp, 9, clock, signal::prbs_initial_state(9, rng));
  for (double& v : u) v += bias;
  return u;
}

// A first-order lag under a unit step held from k = 0: y(k T) = K (1 - e^(-p k T)) at the samples,
// and with a delay of 2.5 samples the same curve shifted by it, exactly.
TEST(FitTfTime, SimulationIsExactAtTheSamples) {
  const RationalTf g{{3.0}, {1.0 / 40.0, 1.0}};
  const double dt = 0.001;
  const std::vector<double> u(200, 1.0);
  const std::vector<double> y = simulate_tf(g, 0.0, dt, u);
  const std::vector<double> yd = simulate_tf(g, 2.5 * dt, dt, u);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    EXPECT_NEAR(y[k], 3.0 * (1.0 - std::exp(-40.0 * t)), 1e-12) << k;
    const double td = std::max(0.0, t - 2.5 * dt);
    EXPECT_NEAR(yd[k], 3.0 * (1.0 - std::exp(-40.0 * td)), 1e-12) << k;
  }
}

// A speed counted over a window of 4 samples is the lag's response averaged over the window:
// (1/W) int_{t-W}^{t} K (1 - e^(-p s)) ds, the integral starting at 0 before the step.
TEST(FitTfTime, WindowedSimulationIsTheMeanOverTheWindow) {
  const RationalTf g{{3.0}, {1.0 / 40.0, 1.0}};
  const double dt = 0.004;
  const double w = 4 * dt;
  const std::vector<double> y = simulate_tf(g, 0.0, dt, std::vector<double>(50, 1.0), 4);
  const auto integral = [](double t) {
    return t <= 0.0 ? 0.0 : 3.0 * (t - (1.0 - std::exp(-40.0 * t)) / 40.0);
  };
  for (std::size_t k = 0; k < y.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    EXPECT_NEAR(y[k], (integral(t) - integral(t - w)) / w, 1e-12) << k;
  }
}

// The board's speed (counts over 16 ms, a row per 4 ms) of the report's plant: fitted through the
// window, the plant itself comes back, not the window's lag.
TEST(FitTfTime, RoundTripThroughTheEstimatorWindow) {
  const double dt = 0.004;
  const std::vector<double> u = prbs(1000, 9.0, 3.0, 3, 5);
  std::vector<double> du(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) du[k] = u[k] - 9.0;
  std::vector<double> y = simulate_tf(report_plant(), 0.0, dt, du, 4);
  for (double& v : y) v += 1400.0;
  table::Table t = run_table(u, y, dt);
  t.meta.set("rpm_estimator", "counts over 0.016 s window, 2048 counts/rev");
  const TimeSeries run = read_time_series(t, "v", "rpm");
  EXPECT_EQ(run.window_samples, 4U);
  const TimeTfFit fit = fit_tf_time(run, {});
  ASSERT_EQ(fit.fit.poles.size(), 2U);
  EXPECT_NEAR(fit.fit.gain, 16.557, 1e-5);
  EXPECT_NEAR(fit.fit.poles[0].corner_rad_s, 65.0, 1e-4);
  EXPECT_NEAR(fit.fit.poles[1].corner_rad_s, 950.0, 0.5);
}

// The report's plant with a 1.5 ms delay, a PRBS about 9 V from the steady state at 9 V: the fit
// gives back the gain, both poles and the delay, and the starting point.
TEST(FitTfTime, RoundTripExactPrbs) {
  const double dt = 0.001;
  const std::vector<double> u = prbs(4000, 9.0, 3.0, 4, 7);
  std::vector<double> du(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) du[k] = u[k] - 9.0;
  std::vector<double> y = simulate_tf(report_plant(), 0.0015, dt, du);
  for (double& v : y) v += 1400.0;
  TfFitOptions o;
  o.fit_delay = true;
  const TimeTfFit fit = fit_tf_time(read_time_series(run_table(u, y, dt), "v", "rpm"), o);
  ASSERT_EQ(fit.fit.poles.size(), 2U);
  EXPECT_NEAR(fit.fit.gain, 16.557, 1e-6);
  EXPECT_NEAR(fit.fit.poles[0].corner_rad_s, 65.0, 1e-5);
  EXPECT_NEAR(fit.fit.poles[1].corner_rad_s, 950.0, 1e-3);
  EXPECT_NEAR(fit.fit.delay_s, 0.0015, 1e-8);
  EXPECT_NEAR(fit.u_ref, 9.0, 1e-6);
  EXPECT_NEAR(fit.y0, 1400.0, 1e-5);
  EXPECT_GT(fit.fit_percent, 99.9999);
}

// A step from rest in rpm with white noise of 2 rpm (seeded): the estimates are within four
// standard errors of the truth, the errors are small, and a held-out run is explained as well.
TEST(FitTfTime, RoundTripNoisyStepWithStandardErrors) {
  const double dt = 0.001;
  const double rpm_per_v = 16.557 * 60.0 / (2.0 * 3.14159265358979323846);
  RationalTf g = report_plant();
  g.num[0] = rpm_per_v;
  std::vector<double> u(1500, 0.0);
  for (std::size_t k = 100; k < u.size(); ++k) u[k] = 6.0;
  std::vector<double> y = simulate_tf(g, 0.0, dt, u);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (double& v : y) v += noise(rng);
  const TimeTfFit fit = fit_tf_time(read_time_series(run_table(u, y, dt), "v", "rpm"), {});
  ASSERT_EQ(fit.fit.poles.size(), 2U);
  EXPECT_NEAR(fit.fit.gain, rpm_per_v, 4.0 * fit.fit.gain_se);
  EXPECT_NEAR(fit.fit.poles[0].corner_rad_s, 65.0, 4.0 * fit.fit.poles[0].corner_se);
  EXPECT_NEAR(fit.fit.poles[1].corner_rad_s, 950.0, 4.0 * fit.fit.poles[1].corner_se);
  EXPECT_LT(fit.fit.gain_se, 0.01 * rpm_per_v);
  EXPECT_LT(fit.fit.poles[0].corner_se, 2.0);
  EXPECT_NEAR(fit.rms, 2.0, 0.1);

  const std::vector<double> u2 = prbs(3000, 8.0, 2.0, 6, 11);
  std::vector<double> du2(u2.size());
  for (std::size_t k = 0; k < u2.size(); ++k) du2[k] = u2[k] - 8.0;
  std::vector<double> y2 = simulate_tf(g, 0.0, dt, du2);
  for (double& v : y2) v += 1200.0 + noise(rng);
  const double held_out = validation_fit_percent(fit, read_time_series(run_table(u2, y2, dt), "v", "rpm"));
  EXPECT_GT(held_out, 95.0);
}

TEST(FitTfTime, LeadingUnmeasuredRowsAreSkippedAndSaid) {
  std::vector<double> u(100, 1.0);
  u[50] = 2.0;
  std::vector<double> y(100, 10.0);
  y[0] = y[1] = y[2] = k_nan;
  const TimeSeries ts = read_time_series(run_table(u, y, 0.004), "v", "rpm");
  EXPECT_EQ(ts.skipped, 3U);
  EXPECT_EQ(ts.u.size(), 97U);
  EXPECT_DOUBLE_EQ(ts.dt_s, 0.004);
  EXPECT_EQ(ts.skipped_note,
            "run.csv: skipped the first 3 rows (lines 4-6): 'rpm' not measured yet (the speed estimator's "
            "warm-up)");
}

TEST(FitTfTime, RefusesWhatCannotBeFitted) {
  std::vector<double> u(100, 1.0);
  const std::vector<double> y(100, 10.0);
  EXPECT_EQ(test::error_of([&] { read_time_series(run_table(u, y, 0.001), "v", "rpm"); }),
            "run.csv: column 'v' never changes: the run excites nothing to fit");
  u[50] = 2.0;
  std::vector<double> gap = y;
  gap[40] = k_nan;
  EXPECT_EQ(test::error_of([&] { read_time_series(run_table(u, gap, 0.001), "v", "rpm"); }),
            "run.csv:44: column 'rpm': an unmeasured value (nan or empty) is not allowed here");
  std::vector<double> none(100, k_nan);
  EXPECT_EQ(test::error_of([&] { read_time_series(run_table(u, none, 0.001), "v", "rpm"); }),
            "run.csv: no row has 'rpm' measured");
  table::Table uneven = run_table(u, y, 0.001);
  uneven.columns[0][60] += 0.0004;
  EXPECT_EQ(
      test::error_of([&] { read_time_series(uneven, "v", "rpm"); }),
      "run.csv:64: column 't': a step of 0.0014 s where the run's is 0.001 s: the time-domain fit needs a "
      "uniformly sampled run");
  EXPECT_EQ(test::error_of([&] {
              read_time_series(run_table(std::vector<double>(20, 1.0), std::vector<double>(20, 1.0), 0.001),
                               "v", "rpm");
            }),
            "run.csv: 20 rows, too short for a time-domain fit (at least 50)");
}

}  // namespace
}  // namespace mcg::fit
