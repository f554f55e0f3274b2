/* excite.c: identification inputs the board plays itself: a PRBS and a staircase (a step is a
 * staircase of one stair), on the duty in open loop or on rpm_cmd in a closed-loop mode.
 *
 * PRBS: a Galois LFSR of order n (2..16) seeded with 1; each bit is held exc_div ticks; a period is
 * 2^n - 1 bits. The level is exc_offset + exc_amp while the bit that leaves the register is 1,
 * exc_offset - exc_amp while it is 0.
 * Staircase: stairs k = 0..exc_steps, each held exc_div ticks, at exc_offset + k exc_amp.
 * After exc_periods periods (0: until exc_run is written 0) the target returns to exc_offset.
 *
 * Start: writing exc_run 1 checks every level against the target's range (duty within
 * duty_min..duty_max, rpm_cmd within its register range) and is refused with MCG_ST_RANGE
 * otherwise. The first level is applied on the first tick that opens a stream sample (at once if
 * the stream is off), before that tick's control update: the capture's first excited sample is
 * then one whole stream sample, and each level acts for exactly exc_div updates. Started with the
 * stream off, the excitation turns the stream on at that tick: the first streamed sample then
 * begins with the first excited tick (the capture's t = 0 is the excitation's start).
 * The per-tick cost is a down-counter; the LFSR step and the target write run once per bit.
 * Fixed point only: every level is an int16 computed at the start or by one addition. */
#include "core.h"

uint8_t MCG_XDATA g_exc_kind;
uint8_t MCG_XDATA g_exc_order;
uint8_t MCG_XDATA g_exc_steps;
uint16_t MCG_XDATA g_exc_div;
int16_t MCG_XDATA g_exc_amp;
int16_t MCG_XDATA g_exc_offset;
uint8_t MCG_XDATA g_exc_periods;
uint8_t MCG_XDATA g_exc_run;

/* Galois toggle masks of maximal-length LFSRs, order 2..16 (period 2^n - 1). */
static MCG_CODE uint16_t k_taps[15] = {0x0003u, 0x0006u, 0x000Cu, 0x0014u, 0x0030u, 0x0060u, 0x00B8u, 0x0110u,
                                       0x0240u, 0x0500u, 0x0829u, 0x100Du, 0x2015u, 0x6000u, 0xD008u};

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
    default: /* MCG_REG_EXC_PERIODS */
      g_exc_periods = (uint8_t)v;
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
  } else {
    s_lo = g_exc_offset;
    s_hi = (int32_t)g_exc_offset + (int32_t)g_exc_amp * g_exc_steps;
    s_period = (uint16_t)(g_exc_steps + 1u);
  }
  if (s_lo > s_hi) { /* a staircase that descends */
    s_hi = s_lo;
    s_lo = (int32_t)g_exc_offset + (int32_t)g_exc_amp * g_exc_steps;
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
  } else if (--s_bit == 0) {
    s_bit = s_period;
    s_lfsr = 1;
    s_level = g_exc_offset;
    if (s_periods != 0 && --s_periods == 0) {
      excite_set_run(0);
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
    } else {
      s_lfsr >>= 1;
      s_level = (int16_t)(g_exc_offset - g_exc_amp);
    }
  }
  apply();
}
