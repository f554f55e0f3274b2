/* bench_excite.c: machine cycles that the excitation generator (excite_tick) adds to the 1 ms tick
 * on the 8051, measured in s51 as bench_tick.c measures the control update (Timer 1 counts machine
 * cycles, its reading overhead subtracted). Sets of 256 ticks: 0 idle (no excitation), 1 PRBS on
 * the duty holding a bit (exc_div 2, the ticks that hold), 2 PRBS on the duty with a new bit every tick
 * (exc_div 1), 3 PRBS on rpm_cmd in closed loop, a new bit every tick (the PI update run after each,
 * untimed), 4 staircase on the duty, a
 * new stair every tick, 5 chirp on the duty, a new level every tick. Figures (min, max u16, sum u32)
 * go to BENCH_XADDR, then the timer overhead and the CRC-16 of the duties a PRBS (as set 2) and a
 * chirp (0.1 -> 50 Hz over 3 s, 400 +- 300, a level every tick) play over 10000 ticks each, and the
 * cycles of the chirp's start (the write of exc_run 1); the run ends at bench_done(). */
#include <8051.h>   /* TMOD, TH1, TL1, TR1 */
#include <stdint.h> /* uint8_t, uint16_t, uint32_t */

#include "core.h" /* core_init, excite_tick, regs_write */

#define BENCH_XADDR 0x9F00u
#define BENCH_RUNS 256u
#define BENCH_SETS 6u
#define BENCH_PLAY_MS 10000u

typedef struct {
  uint16_t min, max;
  uint32_t sum;
} Figures;
static Figures MCG_XDATA MCG_AT(BENCH_XADDR) s_fig[BENCH_SETS];
static uint16_t MCG_XDATA MCG_AT(BENCH_XADDR + BENCH_SETS * sizeof(Figures)) s_overhead;
static uint16_t MCG_XDATA MCG_AT(BENCH_XADDR + BENCH_SETS * sizeof(Figures) + 2u) s_crc;
static uint16_t MCG_XDATA MCG_AT(BENCH_XADDR + BENCH_SETS * sizeof(Figures) + 4u) s_crc_chirp;
static uint16_t MCG_XDATA MCG_AT(BENCH_XADDR + BENCH_SETS * sizeof(Figures) + 6u) s_chirp_start;

/* The timer stopped while it is read: a read that retried when TL1 carried into TH1 added 7 cycles to
 * some figures and not others. */
static uint16_t cycles_now(void) {
  uint16_t t;
  TR1 = 0;
  t = (uint16_t)((uint16_t)TH1 << 8 | TL1);
  TR1 = 1;
  return t;
}

void bench_done(void) {}

static void prbs(uint8_t div, int16_t amp, int16_t offset) {
  regs_write(MCG_REG_EXC_RUN, 0);
  regs_write(MCG_REG_EXC_KIND, MCG_EXC_PRBS);
  regs_write(MCG_REG_EXC_ORDER, 9);
  regs_write(MCG_REG_EXC_DIV, div);
  regs_write(MCG_REG_EXC_AMP, amp);
  regs_write(MCG_REG_EXC_OFFSET, offset);
  regs_write(MCG_REG_EXC_PERIODS, 0);
  regs_write(MCG_REG_EXC_RUN, 1);
}

/* 0.1 -> 50 Hz over 3 s on the duty, 400 +- 300, a level every tick, endless. */
static void chirp(void) {
  regs_write(MCG_REG_EXC_RUN, 0);
  regs_write(MCG_REG_EXC_KIND, MCG_EXC_CHIRP);
  regs_write(MCG_REG_EXC_F0, 10);
  regs_write(MCG_REG_EXC_F1, 5000);
  regs_write(MCG_REG_EXC_SWEEP, 3);
  regs_write(MCG_REG_EXC_DIV, 1);
  regs_write(MCG_REG_EXC_AMP, 300);
  regs_write(MCG_REG_EXC_OFFSET, 400);
  regs_write(MCG_REG_EXC_PERIODS, 0);
  {
    uint16_t MCG_XDATA t0 = cycles_now();
    regs_write(MCG_REG_EXC_RUN, 1); /* the start scales the sine table */
    s_chirp_start = (uint16_t)(cycles_now() - t0 - s_overhead);
  }
}

/* The CRC-16 of the duties the running excitation plays over BENCH_PLAY_MS ticks (its locals in
 * external RAM: the internal RAM is spent). */
static uint16_t play_crc(void) {
  uint16_t MCG_XDATA i;
  uint16_t MCG_XDATA crc = MCG_CRC_INIT;
  for (i = 0; i < BENCH_PLAY_MS; ++i) {
    excite_tick();
    crc = (uint16_t)mcg_crc16_update(crc, (unsigned)g_duty_set & 0xFFu);
    crc = (uint16_t)mcg_crc16_update(crc, (unsigned)g_duty_set >> 8 & 0xFFu);
  }
  return crc;
}

void main(void) {
  uint8_t m;
  uint16_t i;
  core_init();
  TMOD = 0x10; /* Timer 1: 16-bit timer (machine cycles) */
  TH1 = 0;
  TL1 = 0;
  TR1 = 1;
  {
    uint16_t t0 = cycles_now();
    uint16_t t1 = cycles_now();
    s_overhead = (uint16_t)(t1 - t0);
  }
  for (m = 0; m < BENCH_SETS; ++m) {
    if (m == 1) {
      prbs(2, 200, 400);
    } else if (m == 2) {
      prbs(1, 200, 400);
    } else if (m == 3) {
      regs_write(MCG_REG_EXC_RUN, 0);
      regs_write(MCG_REG_B0, 9000);
      regs_write(MCG_REG_B1, -8800);
      regs_write(MCG_REG_MODE, MCG_MODE_PI);
      regs_write(MCG_REG_COMMIT, 1);
      control_tick(0); /* two updates: the command history holds the command, as on a running board */
      control_tick(0);
      prbs(1, 100, 420);
    } else if (m == 4) {
      regs_write(MCG_REG_EXC_RUN, 0);
      regs_write(MCG_REG_MODE, MCG_MODE_OPEN);
      regs_write(MCG_REG_COMMIT, 1);
      regs_write(MCG_REG_EXC_KIND, MCG_EXC_STAIRCASE);
      regs_write(MCG_REG_EXC_STEPS, 100);
      regs_write(MCG_REG_EXC_DIV, 1);
      regs_write(MCG_REG_EXC_AMP, 5);
      regs_write(MCG_REG_EXC_OFFSET, 100);
      regs_write(MCG_REG_EXC_RUN, 1);
    } else if (m == 5) {
      chirp();
    }
    excite_tick(); /* the start tick */
    if (m == 3u) {
      control_tick(0);
    }
    s_fig[m].min = 0xFFFFu;
    s_fig[m].max = 0;
    s_fig[m].sum = 0;
    for (i = 0; i < BENCH_RUNS; ++i) {
      uint16_t t0 = cycles_now();
      uint16_t dt;
      excite_tick();
      dt = (uint16_t)(cycles_now() - t0 - s_overhead);
      if (m == 3u) {
        control_tick(0); /* untimed: the update moves the command history on, as every tick does */
      }
      if (m == 1u && (i & 1u)) {
        continue; /* set 1 times the ticks that hold a bit */
      }
      if (dt < s_fig[m].min) {
        s_fig[m].min = dt;
      }
      if (dt > s_fig[m].max) {
        s_fig[m].max = dt;
      }
      s_fig[m].sum += dt;
    }
  }
  regs_write(MCG_REG_EXC_RUN, 0);
  regs_write(MCG_REG_MODE, MCG_MODE_OPEN);
  regs_write(MCG_REG_COMMIT, 1);
  prbs(1, 200, 400);
  s_crc = play_crc();
  chirp();
  s_crc_chirp = play_crc();
  bench_done();
  for (;;) {
  }
}
