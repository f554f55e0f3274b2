// The controller's shadow set and its commit: writes of mode, gains, format, bias and limits never
// reach the running loop until the commit, which acts between two updates, bumpless, and refuses a
// set that would run away (a closed-loop mode with every gain zero) or contradict itself.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "fw_harness.hpp"

using fwtest::Board;
using fwtest::Bytes;

namespace {

constexpr int k_rpm = 500;

// The error e[n] in pulses per ms for the pulses of one tick (below the limit p_hi at 500 rpm).
double error_of(int pulses) { return std::lround(k_rpm * 524288.0 / 60000.0) / 256.0 - pulses; }

// Pulses of tick n: around the 17.07 pulses/ms of 500 rpm, both signs of error.
std::uint16_t pulses_at(int n) { return static_cast<std::uint16_t>(15 + (n * 7) % 5); }

struct Gains {
  int b0, b1, b2, frac;
};
constexpr Gains k_pi{2000, -1900, 0, 8};
constexpr Gains k_pid{9000, -15000, 6100, 11};

void stage(const Gains& g, std::uint8_t mode) {
  ASSERT_EQ(regs_write(MCG_REG_COEF_FRAC, static_cast<std::int16_t>(g.frac)), MCG_ST_OK);
  ASSERT_EQ(regs_write(MCG_REG_B0, static_cast<std::int16_t>(g.b0)), MCG_ST_OK);
  ASSERT_EQ(regs_write(MCG_REG_B1, static_cast<std::int16_t>(g.b1)), MCG_ST_OK);
  ASSERT_EQ(regs_write(MCG_REG_B2, static_cast<std::int16_t>(g.b2)), MCG_ST_OK);
  ASSERT_EQ(regs_write(MCG_REG_MODE, mode), MCG_ST_OK);
}

// A PI from open loop at duty 300, holding 500 rpm, run for 50 ticks: the state a swap starts from.
void pi_running() {
  host_board_reset();
  ASSERT_EQ(regs_write(MCG_REG_RPM_CMD, k_rpm), MCG_ST_OK);
  ASSERT_EQ(regs_write(MCG_REG_DUTY, 300), MCG_ST_OK);
  host_board_tick(0);
  stage(k_pi, MCG_MODE_PI);
  ASSERT_EQ(regs_write(MCG_REG_COMMIT, 1), MCG_ST_OK);
  for (int n = 0; n < 50; ++n) host_board_tick(pulses_at(n));
}

// Duties of ticks 50..89 after pi_running, with `between(n)` called before tick n.
template <typename F>
std::vector<int> run_on(F between) {
  std::vector<int> duty;
  for (int n = 50; n < 90; ++n) {
    between(n);
    host_board_tick(pulses_at(n));
    duty.push_back(host_board_duty());
  }
  return duty;
}

}  // namespace

TEST(FwCommit, StagedWritesNeverReachTheLoop) {
  pi_running();
  const std::vector<int> alone = run_on([](int) {});
  pi_running();
  // The PID arrives one register per tick, as frames at 9600 baud would bring it.
  const std::vector<int> staged = run_on([](int n) {
    if (n == 52) {
      EXPECT_EQ(regs_write(MCG_REG_COEF_FRAC, k_pid.frac), MCG_ST_OK);
    }
    if (n == 55) {
      EXPECT_EQ(regs_write(MCG_REG_MODE, MCG_MODE_PID), MCG_ST_OK);
    }
    if (n == 58) {
      EXPECT_EQ(regs_write(MCG_REG_B0, k_pid.b0), MCG_ST_OK);
    }
    if (n == 61) {
      EXPECT_EQ(regs_write(MCG_REG_DUTY_MAX, 400), MCG_ST_OK);
    }
  });
  EXPECT_EQ(staged, alone) << "the loop ran on part of the staged set";
  std::int16_t v = 0;
  ASSERT_EQ(regs_read(MCG_REG_MODE, &v), MCG_ST_OK);
  EXPECT_EQ(v, MCG_MODE_PI) << "reads show the active set";
  ASSERT_EQ(regs_read_staged(MCG_REG_MODE, &v), MCG_ST_OK);
  EXPECT_EQ(v, MCG_MODE_PID);
  ASSERT_EQ(regs_read(MCG_REG_COMMIT, &v), MCG_ST_OK);
  EXPECT_EQ(v, 1) << "a staged set is pending";
}

// The first update after the commit runs the whole new set, from the duty the old one left:
// U[n-1] = duty * 2^(F+8), the error history carried on.
TEST(FwCommit, TheNextUpdateRunsTheWholeNewSetBumpless) {
  pi_running();
  std::vector<int> duty;
  const int commit_at = 60;
  double u = 0;
  std::vector<double> e;  // e[n] of every tick from 50
  for (int n = 50; n < 90; ++n) {
    if (n == commit_at) {
      stage(k_pid, MCG_MODE_PID);
      ASSERT_EQ(regs_write(MCG_REG_DUTY_MAX, 900), MCG_ST_OK);
      ASSERT_EQ(regs_write(MCG_REG_COMMIT, 1), MCG_ST_OK);
      u = host_board_duty();
    }
    host_board_tick(pulses_at(n));
    e.push_back(error_of(pulses_at(n)));
    if (n >= commit_at) {
      const std::size_t k = e.size() - 1;
      const double s = std::ldexp(1.0, -k_pid.frac);
      u = std::clamp(u + s * (k_pid.b0 * e[k] + k_pid.b1 * e[k - 1] + k_pid.b2 * e[k - 2]), 0.0, 900.0);
      EXPECT_EQ(host_board_duty(), static_cast<int>(std::floor(u + 0.5))) << "tick " << n;
    }
  }
  std::int16_t v = 0;
  ASSERT_EQ(regs_read(MCG_REG_COMMIT, &v), MCG_ST_OK);
  EXPECT_EQ(v, 0) << "nothing pending after the commit";
  ASSERT_EQ(regs_read(MCG_REG_COEF_FRAC, &v), MCG_ST_OK);
  EXPECT_EQ(v, k_pid.frac);
}

TEST(FwCommit, RefusesAClosedLoopModeWithEveryGainZero) {
  for (const std::uint8_t mode :
       {std::uint8_t{MCG_MODE_P}, std::uint8_t{MCG_MODE_PI}, std::uint8_t{MCG_MODE_PID}}) {
    SCOPED_TRACE(static_cast<int>(mode));
    Board b;
    ASSERT_EQ(b.write(MCG_REG_DUTY, 250), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_MODE, mode), MCG_ST_OK) << "staging is not checked";
    EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_NO_GAINS);
    EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_OPEN));
    EXPECT_EQ(b.read(MCG_REG_COMMIT), 0) << "a refused set is discarded";
    b.run(5);
    EXPECT_EQ(host_board_duty(), 250) << "the rig does not move";
    // A gain of the mode makes it valid: b2 alone for the PID, b1 alone for the PI.
    EXPECT_EQ(b.write(mode == MCG_MODE_P    ? MCG_REG_KP
                      : mode == MCG_MODE_PI ? MCG_REG_B1
                                            : MCG_REG_B2,
                      1),
              MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_MODE, mode), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
    EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(mode));
  }
  Board b;
  ASSERT_EQ(b.set(MCG_REG_B2, 100), MCG_ST_OK);
  EXPECT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_NO_GAINS) << "b2 is not a PI gain";
  EXPECT_EQ(b.set(MCG_REG_KP, 100), MCG_ST_OK);
  EXPECT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PID), MCG_ST_OK);
  EXPECT_EQ(b.set(MCG_REG_B2, 0), MCG_ST_NO_GAINS) << "nor can the running mode lose its last gain";
  EXPECT_EQ(b.read(MCG_REG_B2), 100);
}

TEST(FwCommit, RefusesCrossedLimitsAsAWhole) {
  Board b;
  ASSERT_EQ(b.set(MCG_REG_DUTY_MAX, 300), MCG_ST_OK);
  // Raising both above the old ceiling: the floor first would have crossed it one write at a time.
  EXPECT_EQ(b.write(MCG_REG_DUTY_MIN, 500), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_DUTY_MAX, 800), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
  EXPECT_EQ(b.read(MCG_REG_DUTY_MIN), 500);
  b.run(2);
  EXPECT_EQ(host_board_duty(), 500) << "the open-loop duty follows the raised floor";
  EXPECT_EQ(b.write(MCG_REG_DUTY_MIN, 900), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_LIMITS);
  EXPECT_EQ(b.read(MCG_REG_DUTY_MIN), 500);
  EXPECT_EQ(b.read(MCG_REG_COMMIT), 0);
}

TEST(FwCommit, WriteAnswersTheStagedValueReadTheActiveOne) {
  Board b;
  const auto f = b.request(MCG_CMD_WRITE, Bytes{MCG_REG_KP, 0xF4, 0x01});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->payload, (Bytes{MCG_ST_OK, MCG_REG_KP, 0xF4, 0x01})) << "kp 500 staged";
  EXPECT_EQ(b.read(MCG_REG_KP), 0);
  EXPECT_EQ(b.read(MCG_REG_COMMIT), 1);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 0), MCG_ST_OK);
  EXPECT_EQ(b.read(MCG_REG_COMMIT), 0);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
  EXPECT_EQ(b.read(MCG_REG_KP), 0) << "discarded: the commit had nothing to apply";
}

TEST(FwCommit, DutyIsTheControllersInEveryClosedLoopMode) {
  Board b;
  ASSERT_EQ(b.set(MCG_REG_KP, 100), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_B0, 100), MCG_ST_OK);
  for (const std::uint8_t mode :
       {std::uint8_t{MCG_MODE_P}, std::uint8_t{MCG_MODE_PI}, std::uint8_t{MCG_MODE_PID}}) {
    ASSERT_EQ(b.set(MCG_REG_MODE, mode), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_DUTY, 200), MCG_ST_OWNED) << static_cast<int>(mode);
  }
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_OPEN), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_DUTY, 200), MCG_ST_OK);
}

// A sequence stages like the link and commits with an entry of its own: the PI starts on the tick
// of the commit entry, not before.
TEST(FwCommit, SequenceCommitsOnItsTick) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, k_rpm), MCG_ST_OK);
  Bytes entries{0};
  auto entry = [&](int delay, std::uint8_t reg, int value) {
    const Bytes d = fwtest::le16(delay), v = fwtest::le16(value);
    entries.insert(entries.end(), d.begin(), d.end());
    entries.push_back(reg);
    entries.insert(entries.end(), v.begin(), v.end());
  };
  entry(2, MCG_REG_B0, 4000);
  entry(3, MCG_REG_MODE, MCG_MODE_PI);
  entry(4, MCG_REG_COMMIT, 1);
  ASSERT_EQ(b.request(MCG_CMD_SEQ_WRITE, entries)->payload, (Bytes{MCG_ST_OK, 3}));
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
  std::vector<int> duty;
  for (int t = 1; t <= 14; ++t) {
    host_board_tick(0);
    duty.push_back(host_board_duty());
  }
  // Committed on tick 10 (1 + 2 + 3 + 4): the PI's first update is tick 11's (index 10).
  EXPECT_EQ(duty[9], 0);
  EXPECT_GT(duty[10], 0);
}

namespace {

// A sequence's table of (delay, reg, value) entries, written to the board.
struct Sequence {
  Bytes entries{0};
  Sequence& add(int delay, std::uint8_t reg, int value) {
    const Bytes d = fwtest::le16(delay), v = fwtest::le16(value);
    entries.insert(entries.end(), d.begin(), d.end());
    entries.push_back(reg);
    entries.insert(entries.end(), v.begin(), v.end());
    return *this;
  }
};

// A PI swapped in by a sequence over nine ticks: b0, then the mode, then the commit.
void load_pi_swap(Board& b) {
  Sequence s;
  s.add(2, MCG_REG_B0, 4000).add(3, MCG_REG_MODE, MCG_MODE_PI).add(4, MCG_REG_COMMIT, 1);
  ASSERT_EQ(b.request(MCG_CMD_SEQ_WRITE, s.entries)->payload, (Bytes{MCG_ST_OK, 3}));
}

std::int16_t active(std::uint8_t reg) {
  std::int16_t v = 0;
  EXPECT_EQ(regs_read(reg, &v), MCG_ST_OK);
  return v;
}

}  // namespace

// The link's half-staged set is never committed by a sequence: one that stages does not start.
TEST(FwCommit, ASequenceDoesNotStartOnTheLinksStagedSet) {
  Board b;
  load_pi_swap(b);
  ASSERT_EQ(b.write(MCG_REG_B1, -3900), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_BUSY);
  ASSERT_EQ(b.write(MCG_REG_COMMIT, 0), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
}

// While a sequence owns the set, the link can neither stage into it, nor commit nor drop it half
// done, nor the keypad change a gain; the sequence's whole set becomes active at its commit.
TEST(FwCommit, NoOtherWriterTouchesASequencesSet) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, k_rpm), MCG_ST_OK);
  load_pi_swap(b);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
  for (int t = 1; t <= 4; ++t) host_board_tick(0);  // b0 staged on tick 3
  EXPECT_EQ(active(MCG_REG_FLAGS), MCG_FLAG_SEQ | MCG_FLAG_SEQ_SET);
  EXPECT_EQ(b.write(MCG_REG_B1, -3900), MCG_ST_BUSY);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_BUSY);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 0), MCG_ST_BUSY);
  EXPECT_EQ(regs_apply(MCG_REG_B1, -3900), MCG_ST_BUSY);
  EXPECT_EQ(active(MCG_REG_MODE), MCG_MODE_OPEN);
  for (int t = 5; t <= 10; ++t) host_board_tick(0);
  EXPECT_EQ(active(MCG_REG_MODE), MCG_MODE_PI);
  EXPECT_EQ(active(MCG_REG_B0), 4000);
  EXPECT_EQ(active(MCG_REG_B1), 0);
  EXPECT_EQ(active(MCG_REG_FLAGS), 0);
  EXPECT_EQ(b.write(MCG_REG_B1, -3900), MCG_ST_OK);  // the sequence has ended: the set is free
}

// A sequence stopped between its staged writes and its commit leaves nothing staged for another
// writer to commit: the link's commit then changes nothing.
TEST(FwCommit, AStoppedSequenceDropsItsHalfSet) {
  Board b;
  load_pi_swap(b);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
  for (int t = 1; t <= 4; ++t) host_board_tick(0);
  std::int16_t pending = 0;
  ASSERT_EQ(regs_read(MCG_REG_COMMIT, &pending), MCG_ST_OK);
  ASSERT_EQ(pending, 1);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_STOP), MCG_ST_OK);
  ASSERT_EQ(regs_read(MCG_REG_COMMIT, &pending), MCG_ST_OK);
  EXPECT_EQ(pending, 0);
  EXPECT_EQ(b.write(MCG_REG_COMMIT, 1), MCG_ST_OK);
  EXPECT_EQ(active(MCG_REG_B0), 0);
  EXPECT_EQ(active(MCG_REG_MODE), MCG_MODE_OPEN);
}

// The keypad's change is one commit; it waits for the link's staged set rather than drop it.
TEST(FwCommit, TheKeypadDoesNotDropTheLinksStagedSet) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_B0, 4000), MCG_ST_OK);
  EXPECT_EQ(regs_apply(MCG_REG_DUTY_BIAS, 100), MCG_ST_BUSY);
  std::int16_t b0 = 0;
  ASSERT_EQ(regs_read_staged(MCG_REG_B0, &b0), MCG_ST_OK);
  EXPECT_EQ(b0, 4000);
  ASSERT_EQ(b.write(MCG_REG_COMMIT, 0), MCG_ST_OK);
  EXPECT_EQ(regs_apply(MCG_REG_DUTY_BIAS, 100), MCG_ST_OK);
  EXPECT_EQ(active(MCG_REG_DUTY_BIAS), 100);
}
