// The 1 ms controller and the speed measurement against their equations in double precision.
//
// The fixed-point accumulator is exact (16 x 16 -> 32 products, no overflow by construction), so
// with the same quantised coefficients and command the only difference from the double-precision
// difference equation is the final rounding: |duty - u| <= 0.5 (1/1000 duty), in fact
// duty = floor(u + 0.5) at every step, saturation included.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include "fw_harness.hpp"

using fwtest::Board;

namespace {

constexpr double k_counts_per_rev = 2048.0;

// Exact command in pulses per 1 ms tick.
double rpm_to_counts_per_ms(double rpm) { return rpm * k_counts_per_rev / 60000.0; }

double q8_command(int rpm) { return static_cast<double>(std::lround(rpm * 524288.0 / 60000.0)) / 256.0; }

// e = r - p with p limited to floor((256 r + 8191) / 256), so that e >= -8191/256 (pulses/ms).
double error_of(int rpm, int pulses) {
  const long r_q8 = std::lround(rpm * 524288.0 / 60000.0);
  const long p_hi = (r_q8 + MCG_ERR_LIMIT) / 256;
  return static_cast<double>(r_q8 - 256 * std::min<long>(pulses, p_hi)) / 256.0;
}

struct Coefs {
  int kp = 0, b0 = 0, b1 = 0, b2 = 0;
  int frac = 8;
  int duty_min = 0, duty_max = 1000, bias = 0;
};

void configure(Board& b, const Coefs& c, int rpm_cmd) {
  ASSERT_EQ(b.set(MCG_REG_COEF_FRAC, c.frac), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_KP, c.kp), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_B0, c.b0), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_B1, c.b1), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_B2, c.b2), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_DUTY_MIN, c.duty_min), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_DUTY_MAX, c.duty_max), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_DUTY_BIAS, c.bias), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, rpm_cmd), MCG_ST_OK);
}

// Runs the firmware and the double-precision equation side by side on the same pulse sequence,
// starting from open loop at duty0 (the previous ticks counted no pulses), and returns the largest
// |duty - u|; every step is also checked to be floor(u + 0.5).
// command_steps: (tick, rpm) pairs, the command written just before that tick.
double compare(std::uint8_t mode, const Coefs& c, int rpm_cmd, int duty0,
               const std::vector<std::uint16_t>& pulses,
               const std::vector<std::pair<std::size_t, int>>& command_steps = {}) {
  Board b;
  configure(b, c, rpm_cmd);
  EXPECT_EQ(b.write(MCG_REG_DUTY, duty0), MCG_ST_OK);
  EXPECT_EQ(b.set(MCG_REG_MODE, mode), MCG_ST_OK);

  const double scale = std::ldexp(1.0, -c.frac);
  const double kp = c.kp * scale, b0 = c.b0 * scale, b1 = c.b1 * scale, b2 = c.b2 * scale;
  double e1 = error_of(rpm_cmd, 0), e2 = error_of(rpm_cmd, 0);
  double u_state = duty0;
  double worst = 0;
  for (std::size_t n = 0; n < pulses.size(); ++n) {
    for (const auto& [tick, rpm] : command_steps) {
      if (tick == n) {
        EXPECT_EQ(regs_write(MCG_REG_RPM_CMD, static_cast<std::int16_t>(rpm)), MCG_ST_OK);
        rpm_cmd = rpm;
      }
    }
    host_board_tick(pulses[n]);
    const double e = error_of(rpm_cmd, pulses[n]);
    EXPECT_GE(e, -MCG_ERR_LIMIT / 256.0);
    double u = 0;
    if (mode == MCG_MODE_P) {
      u = std::clamp(c.bias + kp * e, double(c.duty_min), double(c.duty_max));
    } else {
      u_state += b0 * e + b1 * e1 + (mode == MCG_MODE_PID ? b2 * e2 : 0.0);
      u_state = std::clamp(u_state, double(c.duty_min), double(c.duty_max));
      u = u_state;
    }
    e2 = e1;
    e1 = e;
    const int duty = host_board_duty();
    EXPECT_EQ(duty, static_cast<int>(std::floor(u + 0.5))) << "tick " << n;
    worst = std::max(worst, std::abs(duty - u));
  }
  return worst;
}

std::vector<std::uint16_t> random_pulses(std::size_t n, int lo, int hi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> d(lo, hi);
  std::vector<std::uint16_t> p(n);
  for (auto& x : p) {
    x = static_cast<std::uint16_t>(d(rng));
  }
  return p;
}

}  // namespace

TEST(FwControl, CommandConversionIsExactlyRounded) {
  // Every command whose Q8 value fits an int16, both signs: the division-free estimate and its
  // correction give the exactly rounded quotient.
  for (int rpm = -3749; rpm <= 3749; ++rpm) {
    const int q8 = control_rpm_to_q8(static_cast<std::int16_t>(rpm));
    ASSERT_EQ(q8, std::lround(rpm * 524288.0 / 60000.0)) << rpm;
    // Quantisation: at most half a Q8 step, 1/512 count/ms = 0.057 rpm.
    EXPECT_LE(std::abs(q8 / 256.0 - rpm_to_counts_per_ms(rpm)), 1.0 / 512.0 + 1e-12);
  }
}

TEST(FwControl, ProportionalMatchesDoublePrecision) {
  Coefs c;
  c.kp = 3000;  // 11.72 per count/ms at F = 8
  c.bias = 150;
  const auto p = random_pulses(400, 5, 25, 1);
  EXPECT_LE(compare(MCG_MODE_P, c, 420, 0, p), 0.5);
}

TEST(FwControl, ProportionalNegativeGainAndLimitsBelowZero) {
  Coefs c;
  c.kp = -1234;
  c.duty_min = -600;
  c.duty_max = 800;
  c.bias = -20;
  const auto p = random_pulses(400, 0, 40, 2);
  EXPECT_LE(compare(MCG_MODE_P, c, 333, 0, p), 0.5);
}

TEST(FwControl, PiMatchesDoublePrecisionAtEveryFormat) {
  for (int frac : {0, 4, 8, 11}) {  // 11.645 * 2^12 would not fit 16 bits
    SCOPED_TRACE(frac);
    Coefs c;
    c.frac = frac;
    // The report's Tustin PI, (11.645 z - 6.987) / (z - 1), quantised at F fractional bits.
    c.b0 = static_cast<int>(std::lround(std::ldexp(11.645, frac)));
    c.b1 = static_cast<int>(std::lround(std::ldexp(-6.987, frac)));
    const auto p = random_pulses(600, 8, 20, 3 + static_cast<std::uint64_t>(frac));
    EXPECT_LE(compare(MCG_MODE_PI, c, 420, 250, p), 0.5);
  }
}

TEST(FwControl, PidMatchesDoublePrecisionThroughSaturation) {
  Coefs c;
  c.b0 = 9000;
  c.b1 = -15000;
  c.b2 = 6100;
  c.duty_min = 50;
  c.duty_max = 900;
  // Wide pulse swings drive the output into both limits and back.
  const auto p = random_pulses(1500, 0, 40, 4);
  EXPECT_LE(compare(MCG_MODE_PID, c, 600, 400, p), 0.5);
}

// Command steps, also two in consecutive ticks: the stored errors keep the commands of their ticks.
TEST(FwControl, CommandStepsFollowTheDifferenceEquation) {
  Coefs c;
  c.b0 = 7000;
  c.b1 = -12000;
  c.b2 = 5200;
  const auto p = random_pulses(300, 10, 20, 6);
  EXPECT_LE(compare(MCG_MODE_PID, c, 420, 300, p, {{40, 600}, {41, 333}, {120, 700}, {200, 120}}), 0.5);
  Coefs pi;
  pi.b0 = 2981;
  pi.b1 = -1789;
  EXPECT_LE(compare(MCG_MODE_PI, pi, 420, 300, p, {{10, 500}, {12, 450}}), 0.5);
  Coefs prop;
  prop.kp = 2000;
  prop.bias = 100;
  EXPECT_LE(compare(MCG_MODE_P, prop, 420, 0, p, {{50, 700}, {51, 720}}), 0.5);
}

TEST(FwControl, ErrorSaturatesAtItsStatedRange) {
  // A runaway count (200 pulses/ms) and a stalled motor at the top of the range: the pulses are
  // limited so that e >= -MCG_ERR_LIMIT, and Kp e stays within 16 x 14 bits whatever the encoder does.
  Coefs c;
  c.kp = 32767;
  c.frac = 12;
  c.duty_min = -1000;
  c.bias = 0;
  std::vector<std::uint16_t> p{200, 255, 0, 0, 127, 128, 300};
  EXPECT_LE(compare(MCG_MODE_P, c, 720, 0, p), 0.5);
}

// Design coefficients not representable in Q8 (the report's 11.645 and -6.987) cost at most
// |b - B/2^F| <= 2^-(F+1) each: over N steps of |e| <= E the output differs from the unquantised
// equation by at most N (2 * 2^-(F+1)) E + 0.5.
TEST(FwControl, QuantisationErrorWithinItsBound) {
  Board b;
  Coefs c;
  c.b0 = static_cast<int>(std::lround(11.645 * 256));
  c.b1 = static_cast<int>(std::lround(-6.987 * 256));
  configure(b, c, 420);
  ASSERT_EQ(b.write(MCG_REG_DUTY, 300), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
  const auto p = random_pulses(200, 12, 17, 5);
  const double r = q8_command(420);
  double u = 300, e1 = r, worst = 0, emax = 0;
  for (std::size_t n = 0; n < p.size(); ++n) {
    host_board_tick(p[n]);
    const double e = r - p[n];
    u = std::clamp(u + 11.645 * e - 6.987 * e1, 0.0, 1000.0);
    e1 = e;
    emax = std::max({emax, std::abs(e), std::abs(e1)});
    worst = std::max(worst, std::abs(host_board_duty() - u));
    const double bound = static_cast<double>(n + 1) * 2.0 / 512.0 * emax + 0.5;
    ASSERT_LE(std::abs(host_board_duty() - u), bound) << "tick " << n;
  }
  EXPECT_GT(worst, 0.0);
}

namespace {

// A first-order motor with an encoder: speed w (counts/ms) follows K u with time constant tau,
// the encoder delivers whole pulses, the fraction carried over.
struct Motor {
  double w = 0, frac = 0;
  double k = 0.04;                   // counts/ms per 1/1000 duty: full duty = 40 counts/ms = 1172 rpm
  double a = std::exp(-1.0 / 50.0);  // tau = 50 ms
  std::uint16_t step(int duty) {
    w = a * w + (1 - a) * k * duty;
    frac += w;
    const double whole = std::floor(frac);
    frac -= whole;
    return static_cast<std::uint16_t>(whole);
  }
};

}  // namespace

// Closed loop over the range 420 +- 300 rpm: the integral action makes the mean speed equal the
// command (the command itself is exact to 0.057 rpm).
TEST(FwControl, PiHoldsTheCommandAcrossTheRange) {
  for (int rpm : {120, 420, 720}) {
    SCOPED_TRACE(rpm);
    Board b;
    Coefs c;
    c.b0 = 512;   // 2.0
    c.b1 = -486;  // -1.9: Ki T = 0.1
    configure(b, c, rpm);
    ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
    Motor m;
    std::uint16_t p = 0;
    for (int n = 0; n < 3000; ++n) {
      host_board_tick(p);
      p = m.step(host_board_duty());
    }
    long sum = 0;
    for (int n = 0; n < 2000; ++n) {
      host_board_tick(p);
      sum += p;
      p = m.step(host_board_duty());
    }
    const double mean_rpm = static_cast<double>(sum) / 2000.0 * 60000.0 / k_counts_per_rev;
    EXPECT_NEAR(mean_rpm, rpm, 1.0);
  }
}

// Anti-windup: held at the limit for two seconds, the output leaves it on the first tick the error
// changes sign, where an unclamped integrator would stay pinned for as long again.
TEST(FwControl, AntiWindupLeavesTheLimitAtOnce) {
  Board b;
  Coefs c;
  c.b0 = 512;
  c.b1 = -486;
  c.duty_max = 300;  // at most 12 counts/ms = 351 rpm: the 720 rpm command cannot be reached
  configure(b, c, 720);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
  Motor m;
  std::uint16_t p = 0;
  for (int n = 0; n < 2000; ++n) {
    host_board_tick(p);
    p = m.step(host_board_duty());
  }
  EXPECT_EQ(host_board_duty(), 300);
  EXPECT_EQ(b.read(MCG_REG_FLAGS) & static_cast<int>(MCG_FLAG_SATURATED),
            static_cast<int>(MCG_FLAG_SATURATED));
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, 120), MCG_ST_OK);
  host_board_tick(p);
  EXPECT_LT(host_board_duty(), 300);
}

TEST(FwControl, ModeSwitchIsBumpless) {
  Board b;
  b.set_pulses(14);  // requests tick too: keep the motor turning through them
  Coefs c;
  c.b0 = 100;
  c.b1 = -90;
  configure(b, c, 420);
  ASSERT_EQ(b.write(MCG_REG_DUTY, 480), MCG_ST_OK);
  b.run(5, 14);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
  host_board_tick(14);
  // One PI step from 480: b0 e + b1 e1 with e = e1 = 14.336 - 14 counts/ms is 0.013.
  EXPECT_EQ(host_board_duty(), 480);
  b.run(200, 10);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_OPEN), MCG_ST_OK);
  const int held = host_board_duty();
  EXPECT_GT(held, 480);
  host_board_tick(14);
  EXPECT_EQ(host_board_duty(), held) << "open loop continues at the controller's last duty";
  EXPECT_EQ(b.read(MCG_REG_DUTY), held);
}

// Speed display: a 16 ms window, rpm = c * 1875 / 1024. For any speed in the operating range and
// any encoder phase, the reading is within +-(1875/1024 + 0.5) = +-2.33 rpm: better than +-5.
TEST(FwControl, SpeedReadingWithinFiveRpm) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  double worst = 0;
  for (double rpm = 100; rpm <= 740; rpm += 3.7) {
    Board b;
    double acc = phase(rng);
    const double per_ms = rpm_to_counts_per_ms(rpm);
    for (int n = 0; n < 40; ++n) {
      const double before = std::floor(acc);
      acc += per_ms;
      host_board_tick(static_cast<std::uint16_t>(std::floor(acc) - before));
    }
    worst = std::max(worst, std::abs(control_rpm() - rpm));
  }
  EXPECT_LE(worst, 1875.0 / 1024.0 + 0.5);
  EXPECT_GT(worst, 1.0) << "the bound is tight, not vacuous";
}

TEST(FwControl, SpeedRegisterUsesTheWindow) {
  Board b;
  b.run(16, 14);
  EXPECT_EQ(control_rpm(), 410);  // 16 * 14 * 1875 / 1024 = 410.16
  EXPECT_EQ(g_counts_16ms, 224);
}
