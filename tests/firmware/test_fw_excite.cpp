// test_fw_excite.cpp: the excitations the board plays (excite.c), checked against their definitions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fw_harness.hpp"

namespace {

using fwtest::Board;

// Duties the PWM ran, one per tick, for ms ticks.
std::vector<int> duties(Board& b, int ms) {
  std::vector<int> out;
  for (int i = 0; i < ms; ++i) {
    b.run(1);
    out.push_back(host_board_duty());
  }
  return out;
}

void setup_prbs(Board& b, int order, int div, int amp, int offset, int periods) {
  ASSERT_EQ(b.write(MCG_REG_EXC_KIND, MCG_EXC_PRBS), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_ORDER, order), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_DIV, div), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_AMP, amp), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_OFFSET, offset), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_PERIODS, periods), MCG_ST_OK);
}

TEST(FwExcite, PrbsIsMaximalLengthForEveryOrder) {
  for (int order = 2; order <= 16; ++order) {
    Board b;
    setup_prbs(b, order, 1, 100, 300, 2);
    ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
    const int period = (1 << order) - 1;
    const std::vector<int> d = duties(b, 2 * period + 8);
    auto first = d.begin();
    while (first != d.end() && *first == 0) ++first;  // ticks before the first level
    ASSERT_NE(first, d.end()) << "order " << order;
    const std::vector<int> p1(first, first + period);
    const std::vector<int> p2(first + period, first + 2 * period);
    EXPECT_EQ(p1, p2) << "order " << order << ": not periodic with 2^n - 1";
    int ones = 0;
    for (int v : p1) {
      ASSERT_TRUE(v == 400 || v == 200) << "order " << order;
      ones += v == 400;
    }
    EXPECT_EQ(ones, 1 << (order - 1)) << "order " << order << ": an m-sequence holds 2^(n-1) ones";
    // No shorter period: a maximal-length sequence repeats only after 2^n - 1 bits.
    for (int q = 1; q < period; ++q) {
      if (period % q != 0) continue;
      bool periodic = true;
      for (int i = 0; i < period; ++i)
        periodic =
            periodic && p1[static_cast<std::size_t>(i)] == p1[static_cast<std::size_t>((i + q) % period)];
      EXPECT_FALSE(periodic) << "order " << order << " repeats after " << q;
    }
    // After two periods the duty is back at the offset and the run register reads 0.
    EXPECT_EQ(*(first + 2 * period), 300) << "order " << order;
    EXPECT_EQ(b.read(MCG_REG_EXC_RUN), 0);
  }
}

TEST(FwExcite, ClockDividerHoldsEachBit) {
  Board b;
  setup_prbs(b, 4, 3, 50, 100, 1);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  const std::vector<int> d = duties(b, 60);
  auto first = d.begin();
  while (*first == 0) ++first;
  for (int k = 0; k < 15; ++k) {
    EXPECT_EQ(first[3 * k], first[3 * k + 1]);
    EXPECT_EQ(first[3 * k], first[3 * k + 2]);
  }
  EXPECT_EQ(first[45], 100);
  // The Galois register seeded with 1, mask 0x000C: the first bits leave as 1, 0, 0, 1, ...
  EXPECT_EQ(first[0], 150);
  EXPECT_EQ(first[3], 50);
}

TEST(FwExcite, StaircaseClimbsAndReturns) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_EXC_KIND, MCG_EXC_STAIRCASE), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_STEPS, 3), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_DIV, 5), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_AMP, 100), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_OFFSET, 100), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_PERIODS, 1), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_DUTY, 100), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  std::vector<int> d = duties(b, 30);
  std::vector<int> want;
  for (int stair = 0; stair <= 3; ++stair) want.insert(want.end(), 5, 100 + 100 * stair);
  auto first = d.begin();
  while (*first == 100 && first[1] == 100 && first[5] != 200) ++first;
  EXPECT_EQ(std::vector<int>(first, first + 20), want);
  EXPECT_EQ(first[20], 100);
}

/// Makes the board run a PI (b0 300, b1 -290) in closed loop.
void commit_test_pi(Board& b) {
  ASSERT_EQ(b.write(MCG_REG_B0, 300), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_B1, -290), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
}

TEST(FwExcite, ClosedLoopPlaysTheCommand) {
  Board b;
  commit_test_pi(b);
  setup_prbs(b, 3, 10, 50, 400, 1);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  std::vector<int> cmds;
  for (int i = 0; i < 80; ++i) {
    b.run(1);
    int16_t v = 0;
    host_board_reg_read(MCG_REG_RPM_CMD, &v);
    cmds.push_back(v);
  }
  int seen_hi = 0, seen_lo = 0;
  for (int v : cmds) {
    ASSERT_TRUE(v == 350 || v == 400 || v == 450) << v;
    seen_hi += v == 450;
    seen_lo += v == 350;
  }
  EXPECT_EQ(seen_hi, 40);  // 4 ones and 3 zeros in a period of 7 bits, 10 ticks each
  EXPECT_EQ(seen_lo, 30);
  EXPECT_EQ(cmds.back(), 400);
}

// A PRBS on rpm_cmd hands the controller its levels converted at the start: once the command history
// holds a level, the R in use is sum_i b_i r for that level's Q8 command, as after a write of rpm_cmd; the
// amplitude is negative, so the level above the offset is the one the LFSR's zeros select.
TEST(FwExcite, ClosedLoopPrbsGivesTheControllerTheWrittenCommand) {
  Board b;
  commit_test_pi(b);
  setup_prbs(b, 3, 10, -57, 421, 1);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  int checked = 0;
  for (int i = 0; i < 70; ++i) {
    b.run(1);
    int16_t rpm = 0;
    host_board_reg_read(MCG_REG_RPM_CMD, &rpm);
    if (g_ctl_settle != 0) continue;
    const std::int32_t q8 = control_rpm_to_q8(rpm);
    ASSERT_EQ(g_ctl_r_k, 2);
    ASSERT_EQ(g_ctl_r[2], (300 - 290) * q8) << "tick " << i << ", " << rpm << " rpm";
    EXPECT_EQ(g_ctl_p_hi, std::min<int>(85, (q8 + MCG_ERR_LIMIT) >> 8));
    ++checked;
  }
  EXPECT_GE(checked, 50);
}

// A PRBS on rpm_cmd with a new bit every tick sets R from control_levels' table: on every tick R is what
// refresh_r sums for the command and the two before it, R[0] = sum_i b_i r[n-i], R[1] = (b0 + b1) r[n]
// + b2 r[n-1], R[2] = sum_i b_i r[n], from the first level (the command before the start in the
// history) on, and after a commit changes the gains mid-run.
TEST(FwExcite, PrbsOnTheCommandSetsRAsItsSumsEveryTick) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_B0, 300), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_B1, -290), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_B2, 7), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_MODE, MCG_MODE_PID), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, 333), MCG_ST_OK);
  b.run(5);
  setup_prbs(b, 5, 1, 61, 400, 0);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  std::vector<std::int32_t> q = {control_rpm_to_q8(333), control_rpm_to_q8(333)};
  std::int32_t c[3] = {300, -290, 7};
  int changed = 0;
  for (int i = 0; i < 120; ++i) {
    if (i == 60) {
      ASSERT_EQ(b.write(MCG_REG_B0, 280), MCG_ST_OK);
      ASSERT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
      c[0] = 280;
    }
    b.run(1);
    int16_t rpm = 0;
    host_board_reg_read(MCG_REG_RPM_CMD, &rpm);
    q.push_back(control_rpm_to_q8(rpm));
    const std::size_t n = q.size() - 1;
    changed += q[n] != q[n - 1];
    ASSERT_EQ(g_ctl_r[0], c[0] * q[n] + c[1] * q[n - 1] + c[2] * q[n - 2]) << "tick " << i;
    ASSERT_EQ(g_ctl_r[1], (c[0] + c[1]) * q[n] + c[2] * q[n - 1]) << "tick " << i;
    ASSERT_EQ(g_ctl_r[2], (c[0] + c[1] + c[2]) * q[n]) << "tick " << i;
  }
  EXPECT_GE(changed, 40);
}

// A command written while a controller set is staged is committed with that set: R is the new set's
// sum_i b_i r, whether the staged set differs from the active one or repeats it.
TEST(FwExcite, CommandWrittenWhileASetIsStagedIsCommittedWithIt) {
  for (const int b0 : {500, 300}) {
    Board b;
    ASSERT_EQ(b.write(MCG_REG_B0, 300), MCG_ST_OK);
    ASSERT_EQ(b.write(MCG_REG_B1, -290), MCG_ST_OK);
    ASSERT_EQ(b.write(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
    ASSERT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
    b.run(5);
    ASSERT_EQ(b.write(MCG_REG_B0, b0), MCG_ST_OK);
    ASSERT_EQ(b.write(MCG_REG_RPM_CMD, 500), MCG_ST_OK);
    b.run(5);
    ASSERT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(g_ctl_r[k], (b0 - 290) * control_rpm_to_q8(500)) << b0;
  }
}

TEST(FwExcite, RefusesWhatItCannotPlay) {
  Board b;
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE) << "no kind set";
  setup_prbs(b, 5, 1, 200, 900, 1);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE) << "1100 is above duty_max";
  EXPECT_EQ(b.read(MCG_REG_EXC_RUN), 0);
  EXPECT_EQ(b.write(MCG_REG_EXC_OFFSET, 500), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_PERIODS, 0), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_AMP, 10), MCG_ST_BUSY) << "settings are fixed while it runs";
  b.run(5000);
  EXPECT_EQ(b.read(MCG_REG_EXC_RUN), 1) << "0 periods: until stopped";
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 0), MCG_ST_OK);
  b.run(2);
  EXPECT_EQ(host_board_duty(), 500) << "stopping returns the duty to the offset";
  EXPECT_EQ(b.write(MCG_REG_EXC_ORDER, 17), MCG_ST_RANGE);
}

TEST(FwExcite, FirstLevelOpensAStreamSample) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  b.run(2);  // somewhere inside a sample
  ASSERT_EQ(b.write(MCG_REG_EXC_KIND, MCG_EXC_STAIRCASE), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_AMP, 200), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_DIV, 8), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  // The step from 0 to 200 must fill whole stream samples: no sample's mean duty lies between.
  const auto frames = b.run(400);
  int blocks = 0;
  for (const auto& f : frames) {
    if (f.cmd != MCG_MSG_STREAM) continue;
    ++blocks;
    for (unsigned k = 0; k < MCG_STREAM_SAMPLES; ++k) {
      const std::size_t at = MCG_STREAM_HEADER + MCG_STREAM_SAMPLE_BYTES * k;
      int duty = f.payload.at(at) | ((f.payload.at(at + 1) & 0x07) << 8);
      if (duty & 0x400) duty -= 0x800;
      EXPECT_TRUE(duty == 0 || duty == 200) << "a sample straddles a level change: " << duty;
    }
  }
  EXPECT_GT(blocks, 2);
}

}  // namespace

namespace {

// The same 10 s of PRBS that bench/bench_excite.c plays in s51 on the 8051 image: the CRC-16 of the
// duties must be the figure bench-excite.sh reads from s51 (the ctest firmware.excite_s51 passes it).
TEST(FwExcite, HostPlaysTheSequenceTheEightOFiftyOnePlays) {
  fwtest::Board b;
  regs_write(MCG_REG_EXC_RUN, 0);
  regs_write(MCG_REG_EXC_KIND, MCG_EXC_PRBS);
  regs_write(MCG_REG_EXC_ORDER, 9);
  regs_write(MCG_REG_EXC_DIV, 1);
  regs_write(MCG_REG_EXC_AMP, 200);
  regs_write(MCG_REG_EXC_OFFSET, 400);
  regs_write(MCG_REG_EXC_PERIODS, 0);
  ASSERT_EQ(regs_write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  unsigned crc = MCG_CRC_INIT;
  for (int i = 0; i < 10000; ++i) {
    excite_tick();
    const auto d = static_cast<std::uint16_t>(g_duty_set);
    crc = mcg_crc16_update(crc, d & 0xFFu);
    crc = mcg_crc16_update(crc, (d >> 8) & 0xFFu);
  }
  EXPECT_EQ(crc, 0xD226u);
}

}  // namespace

namespace {

// Started with the stream off, the excitation turns it on: the first streamed sample is the first
// excited tick (a staircase from 0 whose first stair is 300 shows 300 in sample 0, not a mean with 0).
TEST(FwExcite, StartTurnsTheStreamOnAtTheFirstLevel) {
  fwtest::Board b;
  ASSERT_EQ(b.write(MCG_REG_EXC_KIND, MCG_EXC_STAIRCASE), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_OFFSET, 300), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_AMP, 100), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_DIV, 64), MCG_ST_OK);
  ASSERT_EQ(b.read(MCG_REG_STREAM), 0);
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  const auto frames = b.run(200);
  std::vector<int> duty;
  for (const auto& f : frames) {
    if (f.cmd != MCG_MSG_STREAM) continue;
    for (unsigned k = 0; k < MCG_STREAM_SAMPLES; ++k) {
      const std::size_t at = MCG_STREAM_HEADER + MCG_STREAM_SAMPLE_BYTES * k;
      int d = f.payload.at(at) | ((f.payload.at(at + 1) & 0x07) << 8);
      if (d & 0x400) d -= 0x800;
      duty.push_back(d);
    }
  }
  ASSERT_GE(duty.size(), 32u);
  for (std::size_t k = 0; k < 16; ++k) EXPECT_EQ(duty[k], 300) << "sample " << k;  // 64 ticks: stair 0
  for (std::size_t k = 16; k < 32; ++k) EXPECT_EQ(duty[k], 400) << "sample " << k;
}

}  // namespace

namespace {

void setup_chirp(fwtest::Board& b, int f0_chz, int f1_chz, int sweep_s, int div, int amp, int offset,
                 int periods) {
  ASSERT_EQ(b.write(MCG_REG_EXC_KIND, MCG_EXC_CHIRP), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_F0, f0_chz), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_F1, f1_chz), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_SWEEP, sweep_s), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_DIV, div), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_AMP, amp), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_OFFSET, offset), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_EXC_PERIODS, periods), MCG_ST_OK);
}

// The level of update k against the sweep's definition in double precision: phase_k (turns) =
// k w0 + (w1 - w0) k (k - 1) / (2 N), w = f exc_div / 1000 Hz. The table's 256 points a turn put a
// level within 2 pi / 256 of the amplitude, and the rounding within half a count, of the sine.
void expect_chirp(const std::vector<int>& level, double f0_hz, double f1_hz, double sweep_s, int div, int amp,
                  int offset) {
  const double n = std::floor(sweep_s * 1000.0 / div);
  const double w0 = f0_hz * div / 1000.0;
  const double w1 = f1_hz * div / 1000.0;
  const double bound = 2.0 * M_PI / 256.0 * std::abs(amp) + 0.5 + 1e-9;
  double worst = 0.0;
  for (std::size_t k = 0; k < level.size(); ++k) {
    const double kk = std::fmod(static_cast<double>(k), n);  // a period restarts at phase 0
    const double phase = kk * w0 + (w1 - w0) * kk * (kk - 1.0) / (2.0 * n);
    const double want = offset + amp * std::sin(2.0 * M_PI * phase);
    worst = std::max(worst, std::abs(level[k] - want));
    ASSERT_LE(std::abs(level[k] - want), bound) << "update " << k << ": " << level[k] << " for " << want;
  }
  EXPECT_GT(worst, 0.5) << "the table's error shows (a test that cannot fail would not)";
}

TEST(FwExcite, ChirpSweepsAsDefined) {
  fwtest::Board b;
  setup_chirp(b, 50, 2000, 2, 1, 300, 400, 1);  // 0.5 -> 20 Hz over 2 s, a level every tick
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  const std::vector<int> d = duties(b, 2000);
  expect_chirp(d, 0.5, 20.0, 2.0, 1, 300, 400);
  b.run(1);
  EXPECT_EQ(host_board_duty(), 400) << "after its one period the duty is back at the offset";
  EXPECT_EQ(b.read(MCG_REG_EXC_RUN), 0);
}

TEST(FwExcite, ChirpFallsHoldsAndRepeats) {
  fwtest::Board b;
  setup_chirp(b, 2500, 100, 1, 4, -150, 500, 2);  // 25 -> 1 Hz over 1 s, a level per 4 ticks, twice
  ASSERT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  const std::vector<int> d = duties(b, 2000);
  std::vector<int> level;
  for (std::size_t k = 0; k < d.size(); k += 4) {
    for (std::size_t i = 1; i < 4; ++i) ASSERT_EQ(d[k + i], d[k]) << "tick " << k + i << " holds its level";
    level.push_back(d[k]);
  }
  expect_chirp(level, 25.0, 1.0, 1.0, 4, -150, 500);
  EXPECT_EQ(std::vector<int>(d.begin(), d.begin() + 1000), std::vector<int>(d.begin() + 1000, d.end()));
  b.run(1);
  EXPECT_EQ(host_board_duty(), 500);
}

TEST(FwExcite, ChirpRefusesFrequenciesAtHalfTheUpdateRate) {
  fwtest::Board b;
  setup_chirp(b, 100, 25000, 10, 2, 100, 400, 1);  // 250 Hz with a level every 2 ms: the Nyquist rate
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE);
  EXPECT_EQ(b.write(MCG_REG_EXC_F1, 24999), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 0), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_F0, 25000), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE) << "a falling sweep from there too";
  EXPECT_EQ(b.write(MCG_REG_EXC_F0, 100), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_AMP, 700), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE) << "400 - 700 is below duty_min";
  EXPECT_EQ(b.write(MCG_REG_EXC_AMP, -400), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK) << "0..800 with the amplitude's sign turned";
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 0), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_DIV, 20000), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_F1, 1), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_F0, 1), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_SWEEP, 10), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_RANGE) << "a sweep shorter than one update";
}

// The same 10 s of chirp that bench/bench_excite.c plays in s51 (see the PRBS's twin above).
TEST(FwExcite, HostPlaysTheChirpTheEightOFiftyOnePlays) {
  fwtest::Board b;
  regs_write(MCG_REG_EXC_RUN, 0);
  regs_write(MCG_REG_EXC_KIND, MCG_EXC_CHIRP);
  regs_write(MCG_REG_EXC_F0, 10);
  regs_write(MCG_REG_EXC_F1, 5000);
  regs_write(MCG_REG_EXC_SWEEP, 3);
  regs_write(MCG_REG_EXC_DIV, 1);
  regs_write(MCG_REG_EXC_AMP, 300);
  regs_write(MCG_REG_EXC_OFFSET, 400);
  regs_write(MCG_REG_EXC_PERIODS, 0);
  ASSERT_EQ(regs_write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
  unsigned crc = MCG_CRC_INIT;
  for (int i = 0; i < 10000; ++i) {
    excite_tick();
    const auto d = static_cast<std::uint16_t>(g_duty_set);
    crc = mcg_crc16_update(crc, d & 0xFFu);
    crc = mcg_crc16_update(crc, (d >> 8) & 0xFFu);
  }
  EXPECT_EQ(crc, 0x548Fu);
}

}  // namespace

namespace {

// A PRBS with a negative amplitude plays offset -+ amp: its range check takes those two levels, not
// the staircase's top stair (500 - 3 x 200 would be below duty_min and refused).
TEST(FwExcite, NegativePrbsAmplitudeIsCheckedOnItsOwnLevels) {
  fwtest::Board b;
  setup_prbs(b, 4, 1, -200, 500, 1);
  ASSERT_EQ(b.write(MCG_REG_EXC_STEPS, 3), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_EXC_RUN, 1), MCG_ST_OK);
}

}  // namespace
