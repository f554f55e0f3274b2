// Excitation generators: schedules, steps, staircase, chirp, multisine crest factor, PRBS.
#include "signal/excitation.hpp"

#include "common/error.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <numeric>

namespace mcg::signal {
namespace {

using ::testing::ElementsAre;
using ::testing::ThrowsMessage;
using ::testing::HasSubstr;

TEST(SignalSchedule, ParsesValueAtTimeLists) {
  const auto c = parse_schedule("6@0.5, 0@0.8,inf@1e0", "--then");
  ASSERT_EQ(c.size(), 3U);
  EXPECT_EQ(c[0].value, 6.0);
  EXPECT_EQ(c[0].time_s, 0.5);
  EXPECT_EQ(c[1].value, 0.0);
  EXPECT_EQ(c[1].time_s, 0.8);
  EXPECT_TRUE(std::isinf(c[2].value));
  EXPECT_EQ(c[2].time_s, 1.0);
}

TEST(SignalSchedule, RejectsMalformedItemsNamingTheOption) {
  EXPECT_THAT([] { parse_schedule("6@0.5,7", "--then"); },
              ThrowsMessage<Error>("--then: '7' is not value@time (e.g. 6@0.5)"));
  EXPECT_THAT([] { parse_schedule("6@0.5,x@1", "--then"); },
              ThrowsMessage<Error>("--then: invalid value 'x' in 'x@1'"));
  EXPECT_THAT([] { parse_schedule("1@0,2@-1", "--clutch-schedule"); },
              ThrowsMessage<Error>("--clutch-schedule: negative time in '2@-1'"));
  EXPECT_THAT([] { parse_schedule("1@1,2@0.5", "--clutch-schedule"); },
              ThrowsMessage<Error>("--clutch-schedule: times must increase ('2@0.5' after 1@1)"));
  EXPECT_THAT([] { parse_schedule("1@1,,2@3", "--then"); },
              ThrowsMessage<Error>(HasSubstr("empty item")));
  EXPECT_THAT([] { parse_schedule("1@inf", "--then"); },
              ThrowsMessage<Error>("--then: invalid time 'inf' in '1@inf'"));
}

TEST(SignalSchedule, HoldsInitialValueUntilFirstChange) {
  const std::vector<Change> c{{1, 0.5}, {2, 1.5}};
  EXPECT_EQ(schedule_value(7, c, 0.0), 7.0);
  EXPECT_EQ(schedule_value(7, c, 0.5), 1.0);
  EXPECT_EQ(schedule_value(7, c, 1.49), 1.0);
  EXPECT_EQ(schedule_value(7, c, 2.0), 2.0);
}

TEST(SignalSchedule, ACursorActsWithinHalfANanosecondOfTheChangeAsTheValueDoes) {
  const std::vector<Change> c{{1, 0.5}, {2, 1.5}};
  ScheduleCursor cursor(7, c);
  EXPECT_EQ(cursor.at(0.0), 7.0);
  EXPECT_EQ(cursor.at(0.5 - 1e-9), 7.0);
  EXPECT_EQ(cursor.at(0.5 - 1e-10), 1.0);
  EXPECT_EQ(cursor.at(1.5), 2.0);
  for (const double t : {0.0, 0.5 - 1e-9, 0.5 - 1e-10, 1.0, 1.5, 9.0}) {
    EXPECT_EQ(schedule_value(7, c, t), ScheduleCursor(7, c).at(t)) << t;
  }
}

TEST(SignalGrid, CoversDurationWithWholeSteps) {
  const auto t = time_grid(0.001, 1.0);
  ASSERT_EQ(t.size(), 1000U);
  EXPECT_EQ(t.front(), 0.0);
  EXPECT_DOUBLE_EQ(t.back(), 0.999);
  EXPECT_EQ(time_grid(0.1, 0.3).size(), 3U);  // 0.3/0.1 = 2.9999999999999996
}

TEST(SignalStep, FollowsLevelAndFurtherSteps) {
  const auto t = time_grid(0.1, 1.0);
  const std::vector<Change> then{{6, 0.5}, {0, 0.8}};
  EXPECT_THAT(step_signal(t, 12, 0.1, then), ElementsAre(0, 12, 12, 12, 12, 6, 6, 6, 0, 0));
  EXPECT_THAT([&] { step_signal(t, 12, 0.5, then); },
              ThrowsMessage<Error>("--then: 6@0.5 does not come after --at 0.5"));
}

TEST(SignalStaircase, PassesZeroInBothDirections) {
  EXPECT_THAT(staircase_levels(2, 2), ElementsAre(0, 1, 2, 1, 0, -1, -2, -1, 0));
  const auto t = time_grid(0.5, 5.0);
  EXPECT_THAT(staircase_signal(t, 2, 2, 1.0), ElementsAre(0, 0, 1, 1, 2, 2, 1, 1, 0, 0));
}

TEST(SignalChirp, InstantaneousFrequencyFollowsTheSweep) {
  // Zero crossings of sin(phi) are at phi = m pi: count them to measure the mean frequency
  // over a window, and compare with the closed form of f(t).
  const double dt = 1e-5;
  const double duration = 2.0;
  const auto t = time_grid(dt, duration);
  for (ChirpSpacing spacing : {ChirpSpacing::linear, ChirpSpacing::log}) {
    const auto x = chirp_signal(t, 1.5, 2.0, 50.0, duration, spacing);
    EXPECT_NEAR(*std::max_element(x.begin(), x.end()), 1.5, 1e-6);
    EXPECT_EQ(x.front(), 0.0);
    int crossings = 0;
    for (std::size_t k = 1; k < x.size(); ++k) crossings += (x[k - 1] < 0) != (x[k] < 0) ? 1 : 0;
    // Total phase over [0, T] is 2 pi f0 T (k - 1)/ln k (log) or pi (f0 + f1) T (linear).
    const double cycles = spacing == ChirpSpacing::linear ? 0.5 * (2.0 + 50.0) * duration
                                                          : 2.0 * duration * (25.0 - 1.0) / std::log(25.0);
    EXPECT_NEAR(crossings, 2.0 * cycles, 2.0);
  }
}

TEST(SignalMultisine, HarmonicsAreDistinctAndInsideTheBand) {
  EXPECT_THAT(multisine_harmonics(1, 10, 10, 1.0, ChirpSpacing::linear),
              ElementsAre(1, 2, 3, 4, 5, 6, 7, 8, 9, 10));
  const auto h = multisine_harmonics(0.5, 200, 30, 2.0, ChirpSpacing::log);
  ASSERT_EQ(h.size(), 30U);
  EXPECT_EQ(h.front(), 1);
  EXPECT_EQ(h.back(), 400);
  for (std::size_t j = 1; j < h.size(); ++j) EXPECT_GT(h[j], h[j - 1]);
  EXPECT_THAT([] { multisine_harmonics(0.2, 10, 5, 1.0, ChirpSpacing::log); },
              ThrowsMessage<Error>("--f0 0.2 Hz is below the base frequency 1/period = 1 Hz"));
  EXPECT_THAT([] { multisine_harmonics(1, 3, 5, 1.0, ChirpSpacing::log); },
              ThrowsMessage<Error>(HasSubstr("holds only 3 harmonics")));
}

TEST(SignalMultisine, SchroederPhasesKeepTheCrestFactorLow) {
  // K equal cosines in phase peak at K with rms sqrt(K/2): crest factor sqrt(2K). Schroeder's
  // phases bring a flat band of consecutive harmonics near 1.7 (Schroeder 1970).
  const std::size_t lines = 31;
  const std::size_t period = 4096;
  std::vector<int> h(lines);
  std::iota(h.begin(), h.end(), 1);
  const std::vector<double> zero(lines, 0.0);
  const auto in_phase = multisine_signal(period, 1.0, period, h, zero);
  EXPECT_NEAR(crest_factor(in_phase), std::sqrt(2.0 * lines), 1e-9);
  const auto schroeder = multisine_signal(period, 1.0, period, h, schroeder_phases(lines));
  EXPECT_LT(crest_factor(schroeder), 1.8);
  EXPECT_GT(crest_factor(schroeder), std::sqrt(2.0) - 1e-12);
  double peak = 0;
  for (double v : schroeder) peak = std::max(peak, std::abs(v));
  EXPECT_DOUBLE_EQ(peak, 1.0);
}

TEST(SignalMultisine, SchroederPhaseFormula) {
  const auto phi = schroeder_phases(4);
  // -pi k(k-1)/K for k = 1..4, K = 4: 0, -pi/2, -3pi/2 = pi/2, -3pi = pi (mod 2 pi).
  EXPECT_NEAR(phi[0], 0.0, 1e-15);
  EXPECT_NEAR(phi[1], -std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(phi[2], std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(std::abs(phi[3]), std::numbers::pi, 1e-12);
}

TEST(SignalMultisine, RotatedLinesMatchTheirCosines) {
  // Each line is rotated sample to sample between exact values: over a long period with
  // harmonics near N/2 it stays within 1e-13 of sum cos(2 pi h k / N + phi), scaled to the peak.
  const std::size_t period = 99991;
  const std::vector<int> h{1, 4999, 49990};
  const std::vector<double> phi{0.3, -2.0, 1.0};
  const auto x = multisine_signal(period, 1.0, period, h, phi);
  std::vector<double> direct(period, 0.0);
  double peak = 0.0;
  for (std::size_t k = 0; k < period; ++k) {
    for (std::size_t j = 0; j < h.size(); ++j) {
      const auto hk = static_cast<double>((static_cast<std::size_t>(h[j]) * k) % period);
      direct[k] += std::cos(2 * std::numbers::pi * hk / static_cast<double>(period) + phi[j]);
    }
    peak = std::max(peak, std::abs(direct[k]));
  }
  for (std::size_t k = 0; k < period; ++k) ASSERT_NEAR(x[k], direct[k] / peak, 1e-13) << "sample " << k;
}

TEST(SignalMultisine, IsPeriodicAndHasPowerOnlyAtItsLines) {
  const std::size_t period = 200;
  const std::vector<int> h{3, 7, 40};
  const auto x = multisine_signal(3 * period, 2.0, period, h, schroeder_phases(3));
  for (std::size_t k = 0; k < period; ++k) {
    EXPECT_EQ(x[k], x[k + period]);
    EXPECT_EQ(x[k], x[k + 2 * period]);
  }
  // DFT over one period: equal amplitude at the three lines, nothing elsewhere.
  std::vector<double> amplitude(period / 2);
  for (std::size_t m = 0; m < period / 2; ++m) {
    double re = 0, im = 0;
    for (std::size_t k = 0; k < period; ++k) {
      const double a = 2 * std::numbers::pi * static_cast<double>(m * k) / static_cast<double>(period);
      re += x[k] * std::cos(a);
      im -= x[k] * std::sin(a);
    }
    amplitude[m] = std::hypot(re, im) * 2 / static_cast<double>(period);
  }
  for (std::size_t m = 0; m < period / 2; ++m) {
    if (m == 3 || m == 7 || m == 40) {
      EXPECT_NEAR(amplitude[m], amplitude[3], 1e-12);
      EXPECT_GT(amplitude[m], 0.5);
    } else {
      EXPECT_NEAR(amplitude[m], 0.0, 1e-12) << "bin " << m;
    }
  }
}

TEST(SignalPrbs, EveryOrderHasMaximalLengthAndIsBalanced) {
  for (int order = k_prbs_min_order; order <= k_prbs_max_order; ++order) {
    const std::uint32_t start = 1;
    Lfsr lfsr(order, start);
    const std::uint64_t period = (std::uint64_t{1} << order) - 1;
    std::uint64_t ones = 0;
    std::uint64_t steps = 0;
    do {
      ones += static_cast<std::uint64_t>(lfsr.next());
      ++steps;
    } while (lfsr.state() != start && steps <= period);
    EXPECT_EQ(steps, period) << "order " << order;
    EXPECT_EQ(ones, (period + 1) / 2) << "order " << order;
  }
}

TEST(SignalPrbs, AutocorrelationIsTwoValued) {
  // A maximal-length +-1 sequence of period P has circular autocorrelation P at lag 0 and
  // -1 at every other lag.
  const int order = 7;
  const std::size_t p = 127;
  const auto x = prbs_signal(p, 1.0, order, 1, 0x55);
  for (std::size_t lag = 0; lag < p; ++lag) {
    double r = 0;
    for (std::size_t k = 0; k < p; ++k) r += x[k] * x[(k + lag) % p];
    EXPECT_EQ(r, lag == 0 ? 127.0 : -1.0) << "lag " << lag;
  }
}

TEST(SignalPrbs, ClockHoldsEachBitAndSeedsReproduce) {
  std::mt19937_64 a(42), b(42), c(43);
  const auto sa = prbs_initial_state(10, a);
  EXPECT_EQ(sa, prbs_initial_state(10, b));
  EXPECT_NE(sa, prbs_initial_state(10, c));
  const auto x = prbs_signal(1000, 0.5, 10, 4, sa);
  for (std::size_t k = 0; k < x.size(); ++k) {
    EXPECT_EQ(std::abs(x[k]), 0.5);
    if (k % 4 != 0) {
      EXPECT_EQ(x[k], x[k - 1]);
    }
  }
}

TEST(SignalAprbs, KeepsSwitchingInstantsWithRandomLevels) {
  std::mt19937_64 rng1(7), rng2(7);
  const auto x = aprbs_signal(4000, 3.0, 9, 5, 0x1f, rng1);
  EXPECT_EQ(x, aprbs_signal(4000, 3.0, 9, 5, 0x1f, rng2));
  const auto p = prbs_signal(4000, 1.0, 9, 5, 0x1f);
  std::size_t levels = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    EXPECT_LE(std::abs(x[k]), 3.0);
    if (k > 0) {
      // The level changes exactly where the PRBS switches.
      EXPECT_EQ(x[k] != x[k - 1], p[k] != p[k - 1]) << "sample " << k;
      levels += x[k] != x[k - 1] ? 1U : 0U;
    }
  }
  EXPECT_GT(levels, 100U);
}

}  // namespace
}  // namespace mcg::signal
