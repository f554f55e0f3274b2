/* bench_tick.c: machine cycles of the 1 ms control update on the 8051, measured in s51.
 *
 * The update as the 80C515 image runs it each tick: read the encoder counter (Timer 0, re-read),
 * difference to the last count, control_tick (speed window, error, controller, compare-register
 * PWM write through the c515 layer). Timer 1 in mode 1 counts machine cycles (f/12); its own
 * reading overhead is measured with an empty interval and subtracted. For P, PI and PID, 256
 * updates with varying encoder counts; min, max and sum of cycles go to external RAM at
 * BENCH_XADDR and the run ends at bench_done(); a fourth set repeats the PID at F = 11, the
 * general output shift. A fifth set swaps controllers as mcg-serial load does: a PI runs, a PID is
 * staged one register per update (BENCH_STAGE_AT..), and committed right before update
 * BENCH_COMMIT_AT, timed with it. The sixth times a commit and the update after it, 256 times,
 * alternating between two PID sets (F = 8 and F = 11, other limits): the main loop's worst pass
 * when a commit arrives (bench/bench-cycles.sh reads the figures). Every duty computed goes to
 * BENCH_OUT_XADDR, where the ucsim test compares them with the C core on the host: the assembly
 * parts of the 8051 build must give the same numbers, and the swap must act on one update. */
#include <8051.h>   /* TMOD, TH0, TL0, TH1, TL1, TR0, TR1 */
#include <stdint.h> /* uint8_t, uint16_t, uint32_t */

#include "board_c515.h" /* C515_ENCODER_READ, board_tick_isr */
#include "core.h"       /* core_init, control_tick, regs_write */
#include "uart_mcs51.h" /* uart_isr (linked with the c515 layer) */

#define BENCH_XADDR 0x9F00u
#define BENCH_RUNS 256u
#define BENCH_OUT_XADDR 0xA000u /* 6 x 256 duties, i16 */
#define BENCH_SETS 6u           /* P, PI, PID at F = 8; PID at F = 11; a swap; commits */
#define BENCH_STAGE_AT 100u     /* swap set: the PID's registers are staged before updates 100..104 */
#define BENCH_COMMIT_AT 128u    /* and committed right before update 128 */

/* Per set: min, max (u16), sum (u32); then the empty-interval overhead. */
typedef struct {
  uint16_t min, max;
  uint32_t sum;
} Figures;
static Figures MCG_XDATA MCG_AT(BENCH_XADDR) s_fig[BENCH_SETS];
static uint16_t MCG_XDATA MCG_AT(BENCH_XADDR + BENCH_SETS * sizeof(Figures)) s_overhead;

static int16_t MCG_XDATA MCG_AT(BENCH_OUT_XADDR) s_out[BENCH_SETS][BENCH_RUNS];
static uint8_t s_last_hi, s_last_lo; /* encoder count at the last update */

static uint16_t cycles_now(void) {
  uint8_t hi, lo;
  do {
    hi = TH1;
    lo = TL1;
  } while (hi != TH1);
  return (uint16_t)((uint16_t)hi << 8 | lo);
}

/* The measured update: encoder read, pulses since the last tick (fewer than 256), control_tick. */
static void update(void) {
  uint8_t hi;
  uint8_t lo;
  uint8_t pulses;
  C515_ENCODER_READ(hi, lo);
  pulses = (uint8_t)(lo - s_last_lo);
  s_last_hi = hi;
  s_last_lo = lo;
  control_tick(pulses);
}

void bench_done(void) {}

/* Stages (untimed) what update i of set m needs: the swap set's PID, one register per update, and
 * the commit set's alternating PIDs. Returns 1 if a commit is to be timed with the update. */
static uint8_t stage(uint8_t m, uint16_t i) {
  if (m == 4u) {
    if (i >= BENCH_STAGE_AT && i < BENCH_STAGE_AT + 5u) {
      static MCG_CODE uint8_t regs[5] = {MCG_REG_MODE, MCG_REG_B0, MCG_REG_B1, MCG_REG_B2, MCG_REG_DUTY_MAX};
      static MCG_CODE int16_t values[5] = {MCG_MODE_PID, 7000, -12000, 5200, 900};
      regs_write(regs[i - BENCH_STAGE_AT], values[i - BENCH_STAGE_AT]);
    }
    return (uint8_t)(i == BENCH_COMMIT_AT);
  }
  if (m == 5u) {
    regs_write(MCG_REG_COEF_FRAC, (i & 1u) ? 11 : 8);
    regs_write(MCG_REG_B0, (i & 1u) ? 30000 : 9000);
    regs_write(MCG_REG_B2, (i & 1u) ? 20000 : 6100);
    regs_write(MCG_REG_DUTY_MIN, (i & 1u) ? -500 : 0);
    return 1;
  }
  return 0;
}

void main(void) {
  uint8_t m;
  uint16_t i;
  core_init();
  TMOD = 0x15; /* Timer 1: 16-bit timer (machine cycles); Timer 0: 16-bit counter (encoder) */
  TH1 = 0;
  TL1 = 0;
  TR1 = 1;
  {
    uint16_t t0 = cycles_now();
    uint16_t t1 = cycles_now();
    s_overhead = (uint16_t)(t1 - t0);
  }
  regs_write(MCG_REG_RPM_CMD, 420);
  regs_write(MCG_REG_KP, 3000);
  regs_write(MCG_REG_B0, 9000);
  regs_write(MCG_REG_B1, -15000);
  regs_write(MCG_REG_B2, 6100);
  regs_write(MCG_REG_DUTY_BIAS, 300);
  for (m = 0; m < BENCH_SETS; ++m) {
    if (m == 3) {
      regs_write(MCG_REG_COEF_FRAC, 11); /* the general output shift */
    } else if (m == 4) {
      regs_write(MCG_REG_COEF_FRAC, 8);
      regs_write(MCG_REG_MODE, MCG_MODE_PI);
    } else if (m < 3) {
      regs_write(MCG_REG_MODE, (int16_t)(MCG_MODE_P + m));
    }
    regs_write(MCG_REG_COMMIT, 1);
    s_fig[m].min = 0xFFFFu;
    s_fig[m].max = 0;
    s_fig[m].sum = 0;
    for (i = 0; i < BENCH_RUNS; ++i) {
      uint16_t t0;
      uint16_t dt = 0;
      /* The encoder moved by 6..30 pulses since the last tick: errors of both signs. */
      uint16_t next = (uint16_t)(((uint16_t)s_last_hi << 8 | s_last_lo) + 6u + (i * 7u) % 25u);
      if (stage(m, i)) {
        t0 = cycles_now();
        regs_write(MCG_REG_COMMIT, 1);
        dt = (uint16_t)(cycles_now() - t0 - s_overhead);
      }
      TH0 = (uint8_t)(next >> 8);
      TL0 = (uint8_t)(next & 0xFFu);
      t0 = cycles_now();
      update();
      dt = (uint16_t)(dt + cycles_now() - t0 - s_overhead);
      if (dt < s_fig[m].min) {
        s_fig[m].min = dt;
      }
      if (dt > s_fig[m].max) {
        s_fig[m].max = dt;
      }
      s_fig[m].sum += dt;
      s_out[m][i] = g_duty_out;
    }
  }
  bench_done();
  for (;;) {
  }
}
