// Frequency-response estimators checked against the closed-form response of a known
// discrete filter, excited by a chirp, a multisine and white noise.
#include "signal/spectrum.hpp"

#include "common/error.hpp"
#include "signal/excitation.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

namespace mcg::signal {
namespace {

using ::testing::ThrowsMessage;
using cplx = std::complex<double>;

constexpr double k_dt = 0.001;  // 1 kHz, the rig's sample rate

// y_k = b0 x_{k-d} + b1 x_{k-d-1} - a1 y_{k-1} - a2 y_{k-2}: a resonant second-order filter
// with a pure delay of d samples, H(z) = z^-d (b0 + b1 z^-1) / (1 + a1 z^-1 + a2 z^-2).
struct Filter {
  double b0 = 0.05, b1 = 0.04, a1 = -1.6, a2 = 0.8;
  std::size_t delay = 3;

  std::vector<double> run(const std::vector<double>& x) const {
    std::vector<double> y(x.size(), 0.0);
    auto xd = [&](std::size_t k, std::size_t back) { return k >= back ? x[k - back] : 0.0; };
    for (std::size_t k = 0; k < x.size(); ++k) {
      y[k] = b0 * xd(k, delay) + b1 * xd(k, delay + 1) - a1 * (k >= 1 ? y[k - 1] : 0.0) -
             a2 * (k >= 2 ? y[k - 2] : 0.0);
    }
    return y;
  }
  cplx response(double f_hz) const {
    const cplx zi = std::polar(1.0, -2 * std::numbers::pi * f_hz * k_dt);  // z^-1
    return std::pow(zi, static_cast<int>(delay)) * (b0 + b1 * zi) / (1.0 + a1 * zi + a2 * zi * zi);
  }
};

double relative_error(cplx estimate, cplx exact) { return std::abs(estimate - exact) / std::abs(exact); }

TEST(SignalWelch, RecoversAKnownFilterFromAChirp) {
  const Filter filter;
  const auto t = time_grid(k_dt, 30.0);
  const auto x = chirp_signal(t, 2.0, 1.0, 450.0, 30.0, ChirpSpacing::linear);
  const auto y = filter.run(x);
  const auto r = welch_h1(x, y, k_dt, 4096, 0.5);
  ASSERT_EQ(r.f_hz.size(), 2048U);
  EXPECT_DOUBLE_EQ(r.f_hz.front(), 1000.0 / 4096);
  EXPECT_DOUBLE_EQ(r.f_hz.back(), 500.0);
  std::size_t checked = 0;
  for (std::size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < 20 || r.f_hz[k] > 420) continue;
    EXPECT_LT(relative_error(r.h[k], filter.response(r.f_hz[k])), 0.01) << r.f_hz[k] << " Hz";
    EXPECT_GT(r.coherence[k], 0.995) << r.f_hz[k] << " Hz";
    ++checked;
  }
  EXPECT_GT(checked, 1600U);
}

TEST(SignalWelch, CoherenceMatchesTheSignalToNoiseRatio) {
  // White input of unit variance, white output noise of variance s2: the expected coherence
  // is |H|^2 / (|H|^2 + s2) at every frequency.
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Filter filter;
  std::vector<double> x(400000);
  for (double& v : x) v = unit(rng);
  auto y = filter.run(x);
  const double s2 = 0.25;
  for (double& v : y) v += std::sqrt(s2) * unit(rng);
  const auto r = welch_h1(x, y, k_dt, 512, 0.5);
  double worst = 0;
  for (std::size_t k = 0; k < r.f_hz.size(); ++k) {
    const double g2 = std::norm(filter.response(r.f_hz[k]));
    worst = std::max(worst, std::abs(r.coherence[k] - g2 / (g2 + s2)));
  }
  EXPECT_LT(worst, 0.06);
}

TEST(SignalWelch, NoiselessLinearDataHasUnitCoherence) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(50000);
  for (double& v : x) v = u(rng);
  const auto r = welch_h1(x, Filter{}.run(x), k_dt, 1024, 0.5);
  for (double c : r.coherence) EXPECT_GT(c, 0.995);
}

TEST(SignalWelch, RejectsShortRecords) {
  const std::vector<double> x(100, 1.0);
  EXPECT_THAT([&] { welch_h1(x, x, k_dt, 256, 0.5); },
              ThrowsMessage<Error>("record too short: 100 samples, one segment needs 256"));
  EXPECT_THAT([&] { welch_h1(x, x, k_dt, 8, 0.5); },
              ThrowsMessage<Error>("--segment 8: needs at least 16 samples"));
}

TEST(SignalWelch, BinsWithoutInputPowerAreNaN) {
  // A pure tone at bin 16 of a 128-sample segment: no other bin carries input power.
  std::vector<double> x(1024);
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = std::sin(2 * std::numbers::pi * 16 * static_cast<double>(k) / 128.0);
  const auto r = welch_h1(x, x, k_dt, 128, 0.0);
  EXPECT_NEAR(std::abs(r.h[15] - 1.0), 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(r.h[40].real()));
  EXPECT_TRUE(std::isnan(r.coherence[40]));
}

TEST(SignalDefaultSegment, PowerOfTwoNearAnEighth) {
  EXPECT_EQ(default_segment(100), 100U);
  EXPECT_EQ(default_segment(20000), 2048U);
  EXPECT_EQ(default_segment(1000000), 65536U);
  EXPECT_EQ(default_segment(3000), 256U);
}

TEST(SignalLines, MultisineGivesTheExactResponseAtItsLines) {
  const Filter filter;
  const std::size_t period = 1000;  // 1 Hz lines at 1 kHz
  const auto h = multisine_harmonics(1.0, 450.0, 40, 1.0, ChirpSpacing::log);
  const auto x = multisine_signal(4 * period, 3.0, period, h, schroeder_phases(h.size()));
  const auto y = filter.run(x);
  const auto r = line_response(x, y, k_dt, period, h);
  ASSERT_EQ(r.f_hz.size(), h.size());
  for (std::size_t j = 0; j < h.size(); ++j) {
    EXPECT_DOUBLE_EQ(r.f_hz[j], h[j] * 1.0);
    EXPECT_LT(relative_error(r.h[j], filter.response(r.f_hz[j])), 1e-9) << r.f_hz[j] << " Hz";
    EXPECT_NEAR(r.coherence[j], 1.0, 1e-9);
  }
}

TEST(SignalLines, OnePeriodHasNoCoherenceAndTooShortFails) {
  const std::vector<int> h{1, 2};
  const auto x = multisine_signal(100, 1.0, 100, h, schroeder_phases(2));
  const auto r = line_response(x, x, k_dt, 100, h);
  EXPECT_TRUE(std::isnan(r.coherence[0]));
  EXPECT_NEAR(std::abs(r.h[1] - 1.0), 0.0, 1e-12);
  EXPECT_THAT([&] { line_response(std::span(x).first(50), std::span(x).first(50), k_dt, 100, h); },
              ThrowsMessage<Error>("record too short: 50 samples, one multisine period needs 100"));
  const std::vector<int> high{50};
  EXPECT_THAT([&] { line_response(x, x, k_dt, 100, high); },
              ThrowsMessage<Error>("line 500 Hz is not between 0 and the Nyquist frequency 500 Hz"));
}

TEST(SignalPhase, UnwrapsAPureDelayIntoAStraightLine) {
  std::vector<cplx> h;
  for (int k = 1; k <= 200; ++k) h.push_back(std::polar(2.0, -2 * std::numbers::pi * k * 0.013));
  const auto phase = unwrapped_phase_deg(h);
  for (int k = 1; k <= 200; ++k) EXPECT_NEAR(phase[static_cast<std::size_t>(k - 1)], -360.0 * k * 0.013, 1e-9);
  EXPECT_NEAR(magnitude_db(h[0]), 20 * std::log10(2.0), 1e-12);
}

TEST(SignalResample, DetectsUnevenSamplingAndInterpolates) {
  const std::vector<double> even{0, 0.001, 0.002, 0.003};
  EXPECT_TRUE(spacing_of(even).uniform);
  const std::vector<double> t{0, 0.001, 0.0021, 0.0029, 0.004, 0.005};
  const auto s = spacing_of(t);
  EXPECT_FALSE(s.uniform);
  EXPECT_NEAR(s.min_dt_s, 0.0008, 1e-15);
  EXPECT_NEAR(s.max_dt_s, 0.0011, 1e-15);
  EXPECT_NEAR(s.median_dt_s, 0.001, 1e-15);
  std::vector<double> y;
  for (double v : t) y.push_back(3 * v + 1);
  const auto r = resample_linear(t, y, 0.001);
  ASSERT_EQ(r.size(), 6U);
  for (std::size_t k = 0; k < r.size(); ++k) EXPECT_NEAR(r[k], 3 * 0.001 * static_cast<double>(k) + 1, 1e-12);
}

}  // namespace
}  // namespace mcg::signal
