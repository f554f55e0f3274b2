/* excite.c: identification inputs the board plays itself: a PRBS, a staircase (a step is a staircase
 * of one stair) and a chirp, on the duty in open loop or on rpm_cmd in a closed-loop mode.
 *
 * PRBS: a Galois LFSR of order n (2..16) seeded with 1; each bit is held exc_div ticks; a period is
 * 2^n - 1 bits. The level is exc_offset + exc_amp while the bit that leaves the register is 1,
 * exc_offset - exc_amp while it is 0.
 * Staircase: stairs k = 0..exc_steps, each held exc_div ticks, at exc_offset + k exc_amp.
 * Chirp: a linear sweep from exc_f0 to exc_f1 over exc_sweep s, one level every exc_div ticks (an
 * update), N = exc_sweep 1000 / exc_div updates a period. A phase accumulator in 1/2^32 turns: the
 * level of update k is exc_offset + round(exc_amp sin(2 pi phase_k)), phase_0 = 0, phase_k+1 =
 * phase_k + w_k, w_k = w(f0) + k (w(f1) - w(f0)) / N rounded toward w(f0), w(f) = f exc_div 2^32 /
 * 1000 Hz (the fraction carried exactly, so w_N = w(f1)). The sine is a quarter-wave table of 65 points
 * (256 a turn, the phase truncated to 8 bits): a level is off the exact sine by at most
 * 2 pi / 256 of exc_amp, and the board plays, streams and regenerates on the host the same levels.
 * After exc_periods periods (0: until exc_run is written 0) the target returns to exc_offset.
 *
 * Start: writing exc_run 1 checks every level against the target's range (duty within
 * duty_min..duty_max, rpm_cmd within its register range) and a chirp's frequencies below half the
 * update rate, and is refused with MCG_ST_RANGE otherwise. The first level is applied on the first
 * tick that opens a stream sample (at once if the stream is off), before that tick's control
 * update: the capture's first excited sample is then one whole stream sample, and each level acts
 * for exactly exc_div updates. Started with the stream off, the excitation turns the stream on at
 * that tick: the first streamed sample then begins with the first excited tick (the capture's t = 0
 * is the excitation's start).
 * The per-tick cost is a down-counter; the LFSR step, the chirp's phase and table step and the
 * target write run once per level. A PRBS on rpm_cmd converts its two levels to the controller's Q8
 * command at the start and has the controller precompute its R for them (control_levels), so that a
 * new bit costs copies, without the conversion or a product. Fixed
 * point only: every level is an int16 computed at the start, by one addition, or by one 16 x 16
 * multiply. */
#include "arith.h" /* arith_mul16 */
#include "core.h"

uint8_t MCG_XDATA g_exc_kind;
uint8_t MCG_XDATA g_exc_order;
uint8_t MCG_XDATA g_exc_steps;
uint16_t MCG_XDATA g_exc_div;
int16_t MCG_XDATA g_exc_amp;
int16_t MCG_XDATA g_exc_offset;
uint8_t MCG_XDATA g_exc_periods;
uint8_t MCG_XDATA g_exc_run;
uint16_t MCG_XDATA g_exc_f0, g_exc_f1, g_exc_sweep;

/* Galois toggle masks of maximal-length LFSRs, order 2..16 (period 2^n - 1). */
static MCG_CODE uint16_t k_taps[15] = {0x0003u, 0x0006u, 0x000Cu, 0x0014u, 0x0030u, 0x0060u, 0x00B8u, 0x0110u,
                                       0x0240u, 0x0500u, 0x0829u, 0x100Du, 0x2015u, 0x6000u, 0xD008u};

/* sin(k pi / 128) in Q15, k = 0..64: a quarter wave. */
static MCG_CODE uint16_t k_sine[65] = {
    0u,     804u,   1608u,  2410u,  3212u,  4011u,  4808u,  5602u,  6393u,  7179u,  7962u,  8739u,  9512u,
    10278u, 11039u, 11793u, 12539u, 13279u, 14010u, 14732u, 15446u, 16151u, 16846u, 17530u, 18204u, 18868u,
    19519u, 20159u, 20787u, 21403u, 22005u, 22594u, 23170u, 23731u, 24279u, 24811u, 25329u, 25832u, 26319u,
    26790u, 27245u, 27683u, 28105u, 28510u, 28898u, 29268u, 29621u, 29956u, 30273u, 30571u, 30852u, 31113u,
    31356u, 31580u, 31785u, 31971u, 32137u, 32285u, 32412u, 32521u, 32609u, 32678u, 32728u, 32757u, 32767u};

static uint8_t MCG_XDATA s_starting;   /* started, waiting for a tick that opens a stream sample */
static uint8_t MCG_XDATA s_stream;     /* started with the stream off: turn it on with the first level */
static uint8_t MCG_XDATA s_on_rpm;     /* target: 1 rpm_cmd (closed loop), 0 duty (open loop) */
static uint16_t MCG_XDATA s_lfsr;      /* PRBS state */
static uint16_t MCG_XDATA s_taps;      /* its toggle mask */
static uint16_t MCG_XDATA s_wait;      /* ticks left at the present level */
static uint16_t MCG_XDATA s_bit;       /* bits (PRBS) or stairs (staircase) left in the period */
static uint16_t MCG_XDATA s_period;    /* bits or stairs per period */
static uint8_t MCG_XDATA s_periods;    /* periods left, 0: endless */
static int16_t MCG_XDATA s_level;      /* the present level (the staircase: its stair) */
static int32_t MCG_XDATA s_lo, s_hi;   /* the lowest and highest level, checked at the start */
static int16_t MCG_XDATA s_q8_up;      /* PRBS on rpm_cmd: offset + amp in Q8 (control_rpm_to_q8) */
static int16_t MCG_XDATA s_q8_down;    /* the same for offset - amp */
static int16_t MCG_XDATA s_q8;         /* the present PRBS level's */
static int16_t MCG_XDATA s_wave[65];   /* chirp: exc_amp k_sine[j] / 2^15, rounded: the table scaled */
static uint32_t MCG_XDATA s_phase;     /* chirp: phase, 1/2^32 turn */
static uint32_t MCG_XDATA s_w;         /* chirp: phase step of the present update */
static uint32_t MCG_XDATA s_w0;        /* chirp: w(exc_f0) */
static uint32_t MCG_XDATA s_dq, s_dr;  /* chirp: |w(f1) - w(f0)| = |s_dq| N + s_dr (s_dq mod 2^32) */
static uint32_t MCG_XDATA s_dunit;     /* chirp: 1 if the frequency rises, -1 (mod 2^32) if it falls */
static uint32_t MCG_XDATA s_frac;      /* chirp: the carried fraction of the step's rise, 0..N-1 */
static uint32_t MCG_XDATA s_n;         /* chirp: updates per sweep (N) */
static uint32_t MCG_XDATA s_left;      /* chirp: updates left in the sweep */

void excite_init(void) {
  g_exc_run = 0;
  s_starting = 0;
}

void excite_set(uint8_t reg, int16_t v) MCG_REENTRANT {
  switch (reg) {
    case MCG_REG_EXC_KIND:
      g_exc_kind = (uint8_t)v;
      break;
    case MCG_REG_EXC_ORDER:
      g_exc_order = (uint8_t)v;
      break;
    case MCG_REG_EXC_STEPS:
      g_exc_steps = (uint8_t)v;
      break;
    case MCG_REG_EXC_DIV:
      g_exc_div = (uint16_t)v;
      break;
    case MCG_REG_EXC_AMP:
      g_exc_amp = v;
      break;
    case MCG_REG_EXC_OFFSET:
      g_exc_offset = v;
      break;
    case MCG_REG_EXC_PERIODS:
      g_exc_periods = (uint8_t)v;
      break;
    case MCG_REG_EXC_F0:
      g_exc_f0 = (uint16_t)v;
      break;
    case MCG_REG_EXC_F1:
      g_exc_f1 = (uint16_t)v;
      break;
    default: /* MCG_REG_EXC_SWEEP */
      g_exc_sweep = (uint16_t)v;
      break;
  }
}

/* Sets the target to s_level. */
static void apply(void) {
  if (s_on_rpm) {
    g_rpm_cmd = s_level;
    control_set_rpm_cmd(s_level);
  } else {
    g_duty_set = s_level;
  }
}

static uint8_t levels_ok(void) {
  if (s_on_rpm) {
    return s_lo >= regs_min(MCG_REG_RPM_CMD) && s_hi <= regs_max(MCG_REG_RPM_CMD);
  }
  return s_lo >= g_duty_min && s_hi <= g_duty_max;
}

/* The phase step of x = f exc_div (f in 1/100 Hz) per update of exc_div ticks, f exc_div 2^32 / 10^5
 * in 1/2^32 turn: x 42949.67296 as x 42949 + x 689 / 1024 (off by less than 1e-8 relative); below
 * half a turn while x < 50000 (the frequency below half the update rate). */
#define CHIRP_NYQUIST 50000u
#define CHIRP_STEP(x) ((x) * (uint32_t)42949u + (((x) * (uint32_t)689u) >> 10))

/* Sets up a chirp's sweep; 0 if it cannot be played (a frequency too high, no whole update).
 * Reentrant: its temporaries go on the stack, as the 8051's internal RAM has no room for them. */
static uint8_t chirp_setup(void) MCG_REENTRANT {
  uint32_t x0 = (uint32_t)g_exc_f0 * g_exc_div;
  uint32_t x1 = (uint32_t)g_exc_f1 * g_exc_div;
  s_n = (uint32_t)g_exc_sweep * (uint32_t)1000u / g_exc_div;
  if (x0 >= (uint32_t)CHIRP_NYQUIST || x1 >= (uint32_t)CHIRP_NYQUIST || s_n == 0) {
    return 0;
  }
  s_w0 = CHIRP_STEP(x0);
  x1 = CHIRP_STEP(x1);
  if (x1 < s_w0) {
    x1 = s_w0 - x1;
    s_dunit = (uint32_t)0u - 1u;
  } else {
    x1 -= s_w0;
    s_dunit = 1u;
  }
  s_dq = x1 / s_n;
  s_dr = x1 % s_n;
  if (s_dunit != 1u) {
    s_dq = (uint32_t)0u - s_dq;
  }
  return 1;
}

/* s_wave: 2 amp k_sine[j] in Q15 is amp sin in Q16, so a level is the product's high word, rounded
 * half up. Not reentrant, its locals in external RAM (see chirp_next). */
static void chirp_scale(void) {
  uint8_t MCG_XDATA j;
  int16_t MCG_XDATA amp2 = (int16_t)(2 * g_exc_amp);
  for (j = 0; j < 65u; ++j) {
    s_wave[j] = (int16_t)((arith_mul16(amp2, (int16_t)k_sine[j]) + (int32_t)0x8000) >> 16);
  }
}

static void chirp_restart(void) {
  s_phase = 0;
  s_w = s_w0;
  s_frac = 0;
  s_left = s_n;
}

/* s_level from the phase, then the phase and its step one update on. Its locals live in external
 * RAM and each 32-bit step is one compound assignment: the 8051's internal RAM has no room for
 * the compiler's temporaries. */
static void chirp_next(void) {
  uint8_t MCG_XDATA idx = (uint8_t)(s_phase >> 24);
  uint8_t MCG_XDATA j = (uint8_t)(idx & 63u);
  if (idx & 64u) {
    j = (uint8_t)(64u - j);
  }
  if (idx & 128u) {
    s_level = (int16_t)(g_exc_offset - s_wave[j]);
  } else {
    s_level = (int16_t)(g_exc_offset + s_wave[j]);
  }
  s_frac += s_dr;
  s_phase += s_w;
  s_w += s_dq;
  if (s_frac >= s_n) {
    s_frac -= s_n;
    s_w += s_dunit;
  }
}

/* At the end of a period: 1 (and stopped) if it was the last. */
static uint8_t last_period(void) {
  if (s_periods != 0 && --s_periods == 0) {
    excite_set_run(0);
    return 1;
  }
  return 0;
}

uint8_t excite_set_run(uint8_t run) {
  if (!run) {
    if (g_exc_run) {
      s_level = g_exc_offset;
      apply();
    }
    g_exc_run = 0;
    s_starting = 0;
    return MCG_ST_OK;
  }
  if (g_exc_kind == MCG_EXC_NONE) {
    return MCG_ST_RANGE;
  }
  s_on_rpm = (uint8_t)(g_mode != MCG_MODE_OPEN);
  if (g_exc_kind == MCG_EXC_PRBS) {
    s_lo = (int32_t)g_exc_offset - g_exc_amp;
    s_hi = (int32_t)g_exc_offset + g_exc_amp;
    s_period = (uint16_t)((1uL << g_exc_order) - 1u);
    s_taps = k_taps[g_exc_order - 2u];
    s_q8_up = control_rpm_to_q8((int16_t)s_hi);
    s_q8_down = control_rpm_to_q8((int16_t)s_lo);
    if (s_on_rpm) {
      control_levels(s_q8_up, s_q8_down);
    }
  } else if (g_exc_kind == MCG_EXC_CHIRP) {
    if (!chirp_setup()) {
      return MCG_ST_RANGE;
    }
    chirp_scale();
    s_lo = (int32_t)g_exc_offset - g_exc_amp;
    s_hi = (int32_t)g_exc_offset + g_exc_amp;
    chirp_restart();
  } else {
    s_lo = g_exc_offset;
    s_hi = (int32_t)g_exc_offset + (int32_t)g_exc_amp * g_exc_steps;
    s_period = (uint16_t)(g_exc_steps + 1u);
  }
  if (s_lo > s_hi) { /* a staircase that descends, or a negative amplitude */
    int32_t t = s_lo;
    s_lo = s_hi;
    s_hi = t;
  }
  if (!levels_ok()) {
    return MCG_ST_RANGE;
  }
  s_lfsr = 1;
  s_level = g_exc_offset;
  s_bit = s_period;
  s_wait = 0;
  s_periods = g_exc_periods;
  s_starting = 1;
  s_stream = (uint8_t)!g_stream_on;
  g_exc_run = 1;
  return MCG_ST_OK;
}

void excite_tick(void) {
  if (!g_exc_run) {
    return;
  }
  if (s_starting) {
    if (!app_stream_sample_opens()) {
      return;
    }
    s_starting = 0;
    if (s_stream) {
      g_stream_on = 1;
    }
  } else if (--s_wait != 0) {
    return;
  } else if (g_exc_kind == MCG_EXC_CHIRP) {
    if (--s_left == 0) {
      if (last_period()) {
        return;
      }
      chirp_restart();
    }
  } else if (--s_bit == 0) {
    s_bit = s_period;
    s_lfsr = 1;
    s_level = g_exc_offset;
    if (last_period()) {
      return;
    }
  } else if (g_exc_kind == MCG_EXC_STAIRCASE) {
    s_level = (int16_t)(s_level + g_exc_amp);
  }
  s_wait = g_exc_div;
  if (g_exc_kind == MCG_EXC_PRBS) {
    if (s_lfsr & 1u) {
      s_lfsr = (uint16_t)((s_lfsr >> 1) ^ s_taps);
      s_level = (int16_t)(g_exc_offset + g_exc_amp);
      s_q8 = s_q8_up;
    } else {
      s_lfsr >>= 1;
      s_level = (int16_t)(g_exc_offset - g_exc_amp);
      s_q8 = s_q8_down;
    }
    if (s_on_rpm) {
      g_rpm_cmd = s_level;
      control_set_q8(s_q8);
      return;
    }
  } else if (g_exc_kind == MCG_EXC_CHIRP) {
    chirp_next();
  }
  apply();
}
