/* bench_tick.c: machine cycles of the 1 ms control update on the 8051, measured in s51.
 *
 * The update as the 80C515 image runs it each tick: read the encoder counter (Timer 0, re-read),
 * difference to the last count, control_tick (speed window, error, controller, compare-register
 * PWM write through the c515 layer). Timer 1 in mode 1 counts machine cycles (f/12); its own
 * reading overhead is measured with an empty interval and subtracted. For P, PI and PID, 256
 * updates with varying encoder counts; min, max and sum of cycles go to external RAM at
 * BENCH_XADDR and the run ends at bench_done(); a fourth set repeats the PID at F = 11, the
 * general output shift (bench/bench-cycles.sh reads them). Every duty
 * computed goes to BENCH_OUT_XADDR, where the ucsim test compares them with the C core on the
 * host: the assembly parts of the 8051 build must give the same numbers. */
#include <8051.h>   /* TMOD, TH0, TL0, TH1, TL1, TR0, TR1 */
#include <stdint.h> /* uint8_t, uint16_t, uint32_t */

#include "board_c515.h" /* C515_ENCODER_READ, board_tick_isr */
#include "core.h"       /* core_init, control_tick, regs_write */
#include "uart_mcs51.h" /* uart_isr (linked with the c515 layer) */

#define BENCH_XADDR 0x9F00u
#define BENCH_RUNS 256u
#define BENCH_OUT_XADDR 0xA000u /* 4 x 256 duties, i16 */
#define BENCH_SETS 4u           /* P, PI, PID at F = 8; PID at F = 11 */

/* Per set (P, PI, PID, PID at F = 11): min, max (u16), sum (u32); then the empty-interval overhead. */
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
    } else {
      regs_write(MCG_REG_MODE, (int16_t)(MCG_MODE_P + m));
    }
    s_fig[m].min = 0xFFFFu;
    s_fig[m].max = 0;
    s_fig[m].sum = 0;
    for (i = 0; i < BENCH_RUNS; ++i) {
      uint16_t t0;
      uint16_t dt;
      /* The encoder moved by 6..30 pulses since the last tick: errors of both signs. */
      uint16_t next = (uint16_t)(((uint16_t)s_last_hi << 8 | s_last_lo) + 6u + (i * 7u) % 25u);
      TH0 = (uint8_t)(next >> 8);
      TL0 = (uint8_t)(next & 0xFFu);
      t0 = cycles_now();
      update();
      dt = (uint16_t)(cycles_now() - t0 - s_overhead);
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
