// Margins, closed-loop poles and gain ranges against loops solved by hand.
#include "common/error.hpp"
#include "linsys/analysis.hpp"
#include "linsys/c2d.hpp"
#include "linsys/parse.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace mcg::linsys {
namespace {

constexpr double k_pi = std::numbers::pi;
constexpr double k_tol = 1e-9;

Tf tf(const char* text) { return parse_tf(text, "test").tf; }
double deg(double rad) { return rad * 180.0 / k_pi; }

TEST(LinsysMargins, TypeOneSecondOrder) {
  // L = K/(s(s+a)): ω²(ω² + a²) = K², PM = atan(a/ω), no phase crossover.
  const double k = 10.0;
  const double a = 1.0;
  const Margins m = margins(tf("10/(s*(s+1))"));
  const double wgc = std::sqrt((-a * a + std::sqrt(a * a * a * a + 4.0 * k * k)) / 2.0);
  ASSERT_EQ(m.gain_crossovers_rad_s.size(), 1u);
  EXPECT_NEAR(m.gain_crossovers_rad_s[0], wgc, k_tol * wgc);
  EXPECT_NEAR(m.pm_deg, deg(std::atan(a / wgc)), k_tol);
  EXPECT_NEAR(m.dm_s, std::atan(a / wgc) / wgc, k_tol);
  EXPECT_TRUE(m.phase_crossovers_rad_s.empty());
  EXPECT_TRUE(std::isinf(m.gm));
}

TEST(LinsysMargins, ThirdOrderLag) {
  // L = 4/(s+1)^3: phase −180° at ω = √3 where |L| = 4/8; |L| = 1 at (1+ω²)^(3/2) = 4.
  const Margins m = margins(tf("4/(s+1)^3"));
  ASSERT_EQ(m.phase_crossovers_rad_s.size(), 1u);
  EXPECT_NEAR(m.phase_crossovers_rad_s[0], std::sqrt(3.0), k_tol);
  EXPECT_NEAR(m.gm, 2.0, k_tol);
  const double wgc = std::sqrt(std::pow(4.0, 2.0 / 3.0) - 1.0);
  EXPECT_NEAR(m.pm_omega_rad_s, wgc, k_tol);
  EXPECT_NEAR(m.pm_deg, 180.0 - 3.0 * deg(std::atan(wgc)), k_tol);
}

TEST(LinsysMargins, IntegratorWithDelayHasEveryPhaseCrossover) {
  // L = K e^(−τs)/s: ω_gc = K, PM = 90° − Kτ, phase crossovers at (π/2 + 2πn)/τ.
  const double k = 20.0;
  const double tau = 0.01;
  const Margins m = margins(tf("20*exp(-0.01*s)/s"));
  ASSERT_EQ(m.gain_crossovers_rad_s.size(), 1u);
  EXPECT_NEAR(m.gain_crossovers_rad_s[0], k, k_tol * k);
  EXPECT_NEAR(m.pm_deg, 90.0 - deg(k * tau), 1e-8);
  EXPECT_NEAR(m.dm_s, (k_pi / 2.0 - k * tau) / k, 1e-12);
  ASSERT_GE(m.phase_crossovers_rad_s.size(), 3u);
  for (std::size_t n = 0; n < 3; ++n) {
    const double w = (k_pi / 2.0 + 2.0 * k_pi * static_cast<double>(n)) / tau;
    EXPECT_NEAR(m.phase_crossovers_rad_s[n], w, 1e-9 * w);
  }
  EXPECT_NEAR(m.gm, k_pi / (2.0 * tau) / k, 1e-9);
}

TEST(LinsysMargins, DiscreteIntegratorCrossesAtNyquist) {
  // L = K/(z−1): |e^(jθ)−1| = 2 sin(θ/2), arg = (π+θ)/2, so θ_gc = 2 asin(K/2),
  // PM = (π − θ_gc)/2; at Nyquist L = −K/2: GM = 2/K, the pole 1 − K leaves at K = 2.
  const double t = 0.001;
  Tf l = tf("0.5/(z-1)");
  l.dt_s = t;
  const Margins m = margins(l);
  const double th = 2.0 * std::asin(0.25);
  ASSERT_EQ(m.gain_crossovers_rad_s.size(), 1u);
  EXPECT_NEAR(m.gain_crossovers_rad_s[0] * t, th, k_tol);
  EXPECT_NEAR(m.pm_deg, deg((k_pi - th) / 2.0), k_tol);
  ASSERT_EQ(m.phase_crossovers_rad_s.size(), 1u);
  EXPECT_NEAR(m.phase_crossovers_rad_s[0], k_pi / t, 1e-9);
  EXPECT_NEAR(m.gm, 4.0, k_tol);
  const auto ranges = stable_gain_ranges(l);
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_EQ(ranges[0].k_low, 0.0);
  EXPECT_NEAR(ranges[0].k_high, 4.0, k_tol);
}

TEST(LinsysMargins, ConditionallyStableLoopHasTwoGainRanges) {
  // L = K(s+1)²/s³ is unstable for small K: s³ + Ks² + 2Ks + K is Hurwitz iff 2K² > K, K > 1/2.
  const auto ranges = stable_gain_ranges(tf("(s+1)^2/s^3"));
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_NEAR(ranges[0].k_low, 0.5, 1e-9);
  EXPECT_TRUE(std::isinf(ranges[0].k_high));
}

TEST(LinsysMargins, ClosedLoopPolesAndStability) {
  const auto poles = closed_loop_poles(tf("2/(s+1)"));
  ASSERT_EQ(poles.size(), 1u);
  EXPECT_NEAR(poles[0].real(), -3.0, 1e-12);
  EXPECT_TRUE(is_stable(poles, Domain::s));
  EXPECT_FALSE(is_stable(closed_loop_poles(tf("8/(s+1)^3")), Domain::s));
  bool padded = false;
  EXPECT_TRUE(is_stable(closed_loop_poles(tf("20*exp(-0.01*s)/s"), &padded), Domain::s));
  EXPECT_TRUE(padded);
}

TEST(LinsysMargins, RejectsImproperLoop) { EXPECT_THROW(margins(tf("s^2/(s+1)")), mcg::Error); }

}  // namespace
}  // namespace mcg::linsys

namespace mcg::linsys {
namespace {

TEST(LinsysMargins, StabilityIsDecidedOrRefused) {
  // Roots of (s+1)^12 + 1 have Re s = −1 + cos((2k+1)π/12) <= −0.034: stable.
  EXPECT_TRUE(closed_loop_stable(parse_tf("1/(s+1)^12", "t").tf));
  // (s+1)^64 + 1: every root has Re s <= −0.0012 (it was called unstable).
  EXPECT_TRUE(closed_loop_stable(parse_tf("1/(s+1)^64", "t").tf));
  // A sampled cluster: 1/(s+1)^6 through a ZOH at 1 ms has closed-loop poles 1.3e-4 inside the
  // unit circle, and rounding its coefficients moves them by 1e-3: refused, not called unstable.
  const Tf zoh = c2d(parse_tf("1/(s+1)^6", "t").tf, 0.001, C2dMethod::zoh, 0.0, "t");
  EXPECT_THROW((void)closed_loop_stable(zoh), mcg::Error);
  // (1 + 1e308) s + 1e-308: its root −1e-616 underflows, its sign does not.
  EXPECT_TRUE(closed_loop_stable(parse_tf("1e308*s/(s+1e-308)", "t").tf));
  // Poles on the axis exactly (s² + 1) are not stable.
  EXPECT_FALSE(closed_loop_stable(parse_tf("1/s^2", "t").tf));
  EXPECT_TRUE(schur_cohn_stable({1.0, -0.5}));
  EXPECT_FALSE(schur_cohn_stable({1.0, -1.5}));
  EXPECT_FALSE(schur_cohn_stable({1.0, 0.0, 1.0}));
}

TEST(LinsysMargins, AnIllPosedGainSplitsTheStableRanges) {
  // L = −1 (−1 − 0/z): 1 + K·L = 1 − K is stable for every K but 1, where it vanishes.
  Tf g = parse_tf("-1-0/z", "t").tf;
  g.dt_s = 0.001;
  g = fold_delay(g, "t");
  EXPECT_FALSE(closed_loop_stable(g));
  const auto ranges = stable_gain_ranges(g);
  ASSERT_EQ(ranges.size(), 2u);
  EXPECT_EQ(ranges[0].k_low, 0.0);
  EXPECT_EQ(ranges[0].k_high, 1.0);
  EXPECT_EQ(ranges[1].k_low, 1.0);
  EXPECT_TRUE(std::isinf(ranges[1].k_high));
}

TEST(LinsysMargins, StabilityAgreesWithTheStableGainRange) {
  // A day-long delay on 1/(s+1): gains below 1 are stable, and so is K = 1 itself.
  Tf g = parse_tf("1/(s+1)", "t").tf;
  g.delay_s = 1e9;
  const auto ranges = stable_gain_ranges(g);
  ASSERT_FALSE(ranges.empty());
  EXPECT_EQ(ranges.front().k_low, 0.0);
  EXPECT_GT(ranges.front().k_high, 1.0);
}

}  // namespace
}  // namespace mcg::linsys
