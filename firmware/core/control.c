/* control.c: encoder speed over a 16 ms window and the 1 ms P / PI / PID controller in fixed point.
 *
 * Error, Q8 pulses per tick:
 *   e[n] = r[n] - 256 p[n],  r = rpm_cmd * 2048 * 256 / 60000 (rounded),  p[n] = pulses in tick n,
 *   p[n] limited to p_hi = floor((r + 8191) / 256), so that -8191 <= e[n] <= r.
 * Output u in 1/1000 duty, held in an int32 accumulator U in Q(F + 8), F = g_coef_frac:
 *   P:    U[n] = bias * 2^(F+8) + Kp e[n]
 *   PI:   U[n] = sat(U[n-1] + b0 e[n] + b1 e[n-1])
 *   PID:  U[n] = sat(U[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2])
 *   u[n] = (U[n] + 2^(F+7)) >> (F+8)   (round half up)
 * sat() limits to [duty_min, duty_max] * 2^(F+8): the incremental form stops integrating at the
 * limit (anti-windup). Each product is 16 x 16 -> 32 bits; |coef| <= 2^15 and |e| <= 2^13 bound every
 * product by 2^28 and, with |U| <= 1000 * 2^20, the sum stays below 2^31 for F <= 12: no overflow.
 *
 * Evaluation (exactly the sums above, arranged for an 8-bit multiplier):
 *   sum_i b_i e[n-i] = R[n] - 256 sum_i b_i p[n-i],   R[n] = sum_i b_i r[n-i]
 * R changes only when the command or a coefficient does: it is computed then, for the next three
 * ticks (control_refresh). The pulse part goes to arith_pid_sum (arith.h): three 16 x 8 products.
 *
 * Speed: a 16 ms window gives rpm = c * 60000 / (2048 * 16) = c * 1875 / 1024 with c the pulses in
 * the window. One pulse more or less (window phase) is 1.83 rpm, rounding adds 0.5 rpm: +-2.4 rpm,
 * inside the required +-5 rpm (the report's +-10 rpm corresponds to a 3 ms window). */
#include "arith.h" /* arith_mul16 */
#include "core.h"
#include "hal.h" /* hal_pwm_write */

CtlSet MCG_XDATA g_ctl_shadow;
int16_t MCG_XDATA g_kp, g_b0, g_b1, g_b2;
uint8_t MCG_XDATA g_coef_frac;
int16_t MCG_XDATA g_duty_min, g_duty_max, g_duty_bias;
int16_t g_duty_out;
uint8_t g_saturated;
uint16_t MCG_XDATA g_counts_16ms;
ArithPid g_pid;

static uint8_t MCG_IDATA s_window[MCG_SPEED_WINDOW_MS]; /* pulses per tick, ring */
static uint8_t MCG_XDATA s_window_pos;
static int16_t s_r_q8;               /* command r[n], Q8 pulses per tick */
static int16_t MCG_XDATA s_r1, s_r2; /* r[n-1], r[n-2]: the commands of the last two ticks */
static int32_t MCG_XDATA s_u_bias;   /* P-mode bias in Q(F+8) */
/* What the shadow set derives, kept current as it is written, so that a commit only copies: */
static int16_t MCG_XDATA s_next_scale;               /* 2^F */
static int32_t MCG_XDATA s_next_u_min, s_next_u_max; /* limits in Q(F+8) */
static int32_t MCG_XDATA s_next_u_bias;              /* bias in Q(F+8) */
static int32_t MCG_XDATA s_next_r;                   /* R once the command is settled */
static uint16_t MCG_XDATA s_next_bp[3];              /* operands of arith_pid_sum */
/* The MCG_WRITER_* that wrote the shadow set since the last commit or discard, or 0. */
static uint8_t MCG_XDATA s_staged;
/* Two commands a PRBS on rpm_cmd alternates between (control_levels), the command before them, and the
 * R each combination of the command and the two before it gives with the active set (refresh_r's sums):
 *   r0[k 8 + h] = c0 q_k + c1 q_k1 + c2 q_k2, h = k1 2 + k2 (k1, k2 < 2) or 4 + k1 (k2 = 2);
 *   r1[k 4 + k1] = (c0 + c1) q_k + c2 q_k1;  r2[k] = (c0 + c1 + c2) q_k;  k < 2, k1, k2 <= 2.
 * A new level is then three copies where the products and their 32-bit sums took about 600 cycles on
 * the 8051 (the PI update with a new level was 1.13 ms). */
static int16_t MCG_XDATA s_lv_q[3];
static uint8_t MCG_XDATA s_lv_ok; /* the table holds the active set's R (no commit since) */
static int32_t MCG_XDATA s_lv_r0[16], s_lv_r1[8], s_lv_r2[2];
static int32_t MCG_XDATA s_lv_p[3][3]; /* c_i q_k (the bias added to c0 q_k in P mode) */
uint8_t g_ctl_p_hi;
int32_t MCG_IDATA g_ctl_r[3];
uint8_t g_ctl_r_k;
int32_t g_ctl_u;
int32_t g_ctl_u_min, g_ctl_u_max;
uint8_t g_ctl_shift;
uint8_t g_ctl_settle;

/* x * 2^(F+8) = (x * scale) * 2^8 with scale = 2^F <= 2^12: one 16 x 16 product and a byte shift,
 * not SDCC's 32 x 32 multiply (about 700 cycles on the 8051). The shift is on the unsigned value:
 * shifting a negative one is undefined in C. */
static int16_t MCG_XDATA s_scale; /* 2^F of the active set */
static int32_t scale_up(int16_t x) {
  return (int32_t)((uint32_t)arith_mul16(x, s_scale) << MCG_ERR_FRAC_BITS);
}
/* The same in the shadow set's format. */
static int32_t scale_next(int16_t x) {
  return (int32_t)((uint32_t)arith_mul16(x, s_next_scale) << MCG_ERR_FRAC_BITS);
}
static void next_r(void);
static void refresh_r(void);
static uint8_t level_r(void);

static void rescale(void) {
  g_ctl_shift = (uint8_t)(g_coef_frac + MCG_ERR_FRAC_BITS);
  s_scale = (int16_t)(1 << g_coef_frac);
  g_ctl_u_min = scale_up(g_duty_min);
  g_ctl_u_max = scale_up(g_duty_max);
  s_u_bias = scale_up(g_duty_bias);
  g_ctl_u = scale_up(g_duty_out);
}

/* round(rpm 524288 / 60000), half away from zero: 2048 * 256 = 524288 counts * 2^8 per revolution,
 * 60000 ms per minute. For a = |rpm|: round(a 2^14 / 1875) = 8 a + floor((1384 a + 937) / 1875), as
 * 2^14 = 8 * 1875 + 1384 and 1875 is odd. The quotient is estimated as (24187 a) >> 15 (24187 / 2^15
 * just below 1384 / 1875), which is short by at most 1 for a <= 32767: one remainder test corrects
 * it. Two 16 x 16 products instead of SDCC's 32-bit division (the level change in closed loop took
 * 2.8 ms with it). Exact while the result fits an int16 (|rpm| <= 3749). */
int16_t control_rpm_to_q8(int16_t rpm) {
  MCG_SLOW int16_t a = rpm < 0 ? (int16_t)-rpm : rpm;
  MCG_SLOW uint32_t p = (uint32_t)arith_mul16(a, 24187);
  MCG_SLOW uint16_t q = (uint16_t)(p >> 15);
  /* 1384 a + 937 - 1875 q lies in 0..3749: exact in 16 bits, mod 2^16. */
  if ((uint16_t)((uint16_t)a * 1384u + 937u - q * 1875u) >= 1875u) {
    ++q;
  }
  q = (uint16_t)(q + (uint16_t)a * 8u);
  return rpm < 0 ? (int16_t) - (int16_t)q : (int16_t)q;
}

int16_t control_rpm(void) {
  return (int16_t)(((uint32_t)g_counts_16ms * MCG_RPM_PER_WINDOW_NUM + MCG_RPM_PER_WINDOW_DEN / 2u) /
                   MCG_RPM_PER_WINDOW_DEN);
}

void control_init(void) {
  uint8_t i;
  for (i = 0; i < MCG_SPEED_WINDOW_MS; ++i) {
    s_window[i] = 0;
  }
  s_window_pos = 0;
  g_counts_16ms = 0;
  g_kp = 0;
  g_b0 = 0;
  g_b1 = 0;
  g_b2 = 0;
  /* Neutral until regs_init writes the registers' power-on values. */
  g_coef_frac = 0;
  g_duty_min = 0;
  g_duty_max = 0;
  g_duty_bias = 0;
  g_duty_out = 0;
  g_saturated = 0;
  s_r_q8 = 0;
  s_r1 = 0;
  s_r2 = 0;
  g_ctl_settle = 0;
  s_lv_ok = 0;
  for (i = 0; i < 3; ++i) {
    g_pid.p[i] = 0;
  }
  g_ctl_p_hi = 85;
  rescale();
  control_refresh();
  control_discard();
}

void control_set_rpm_cmd(int16_t rpm) { control_set_q8(control_rpm_to_q8(rpm)); }

void control_set_q8(int16_t r_q8) {
  int16_t hi;
  s_r_q8 = r_q8;
  hi = (int16_t)((s_r_q8 + MCG_ERR_LIMIT) >> 8);
  /* 56 at 720 rpm; never above 85, so that three pulse counts sum to at most 255 */
  g_ctl_p_hi = hi > 85 ? 85u : (uint8_t)hi;
  g_ctl_settle = 2; /* the tick shifts the command history until it holds the new one twice */
  if (!s_staged && level_r()) {
    s_next_r = g_ctl_r[2];
    return;
  }
  refresh_r();
  /* Unstaged, the shadow set is the active one, whose settled R control_refresh just gave. */
  if (s_staged) {
    next_r();
  } else {
    s_next_r = g_ctl_r[2];
  }
}

static int16_t MCG_XDATA s_c0, s_c1, s_c2; /* the active mode's coefficients (0 where it has none) */

/* s_c0..2 and their offset-binary operands of arith_pid_sum. */
static void active_bp(void) {
  s_c0 = 0;
  s_c1 = 0;
  s_c2 = 0;
  if (g_mode == MCG_MODE_P) {
    s_c0 = g_kp;
  } else if (g_mode != MCG_MODE_OPEN) {
    s_c0 = g_b0;
    s_c1 = g_b1;
    if (g_mode == MCG_MODE_PID) {
      s_c2 = g_b2;
    }
  }
  g_pid.bp[0] = (uint16_t)((uint16_t)s_c0 ^ 0x8000u);
  g_pid.bp[1] = (uint16_t)((uint16_t)s_c1 ^ 0x8000u);
  g_pid.bp[2] = (uint16_t)((uint16_t)s_c2 ^ 0x8000u);
}

/* R for the next three ticks from the active mode's coefficients c_i and the command history:
 *   R[k] = sum_i c_i r[n+k-i],  r[m] = the command for m >= n, s_r1, s_r2 before.
 * Once the history holds the command (g_ctl_settle == 0: s_r1 = s_r2 = r), all three are equal. The
 * products of a zero c2 (P, PI) are skipped: a new command costs three products in PI, not seven. */
void control_refresh(void) {
  active_bp();
  refresh_r();
}

/* control_refresh's R alone, for a new command: the coefficients (s_c0..2) from the operands g_pid.bp,
 * which active_bp or a commit left for the active set. */
static void refresh_r(void) {
  MCG_SLOW int32_t now;
  s_c0 = (int16_t)(g_pid.bp[0] ^ 0x8000u);
  s_c1 = (int16_t)(g_pid.bp[1] ^ 0x8000u);
  s_c2 = (int16_t)(g_pid.bp[2] ^ 0x8000u);
  now = arith_mul16(s_c0, s_r_q8);
  if (g_mode == MCG_MODE_P) {
    now += s_u_bias;
  }
  if (g_ctl_settle != 0) {
    g_ctl_r[0] = now + arith_mul16(s_c1, s_r1);
  }
  now += arith_mul16(s_c1, s_r_q8);
  g_ctl_r[1] = now;
  g_ctl_r[2] = now;
  if (s_c2 != 0) {
    g_ctl_r[2] += arith_mul16(s_c2, s_r_q8);
    if (g_ctl_settle != 0) {
      g_ctl_r[1] += arith_mul16(s_c2, s_r1);
      g_ctl_r[0] += arith_mul16(s_c2, s_r2);
    }
  }
  if (g_ctl_settle == 0) {
    g_ctl_r[0] = g_ctl_r[2];
    g_ctl_r[1] = g_ctl_r[2];
  }
  g_ctl_r_k = 0;
}

void control_levels(int16_t q_a, int16_t q_b) MCG_REENTRANT {
  uint8_t k;
  uint8_t h;
  s_lv_q[0] = q_a;
  s_lv_q[1] = q_b;
  s_lv_q[2] = s_r_q8;
  s_c0 = (int16_t)(g_pid.bp[0] ^ 0x8000u);
  s_c1 = (int16_t)(g_pid.bp[1] ^ 0x8000u);
  s_c2 = (int16_t)(g_pid.bp[2] ^ 0x8000u);
  for (k = 0; k < 3u; ++k) {
    s_lv_p[0][k] = arith_mul16(s_c0, s_lv_q[k]);
    if (g_mode == MCG_MODE_P) {
      s_lv_p[0][k] += s_u_bias;
    }
    s_lv_p[1][k] = arith_mul16(s_c1, s_lv_q[k]);
    s_lv_p[2][k] = arith_mul16(s_c2, s_lv_q[k]);
  }
  /* mod 2^32, as refresh_r sums them */
  for (k = 0; k < 2u; ++k) {
    for (h = 0; h < 7u; ++h) {
      uint8_t k1 = h < 4u ? (uint8_t)(h >> 1) : (uint8_t)(h - 4u);
      uint8_t k2 = h < 4u ? (uint8_t)(h & 1u) : 2u;
      s_lv_r0[k * 8u + h] =
          (int32_t)((uint32_t)s_lv_p[0][k] + (uint32_t)s_lv_p[1][k1] + (uint32_t)s_lv_p[2][k2]);
    }
    for (h = 0; h < 3u; ++h) {
      s_lv_r1[k * 4u + h] =
          (int32_t)((uint32_t)s_lv_p[0][k] + (uint32_t)s_lv_p[1][k] + (uint32_t)s_lv_p[2][h]);
    }
    s_lv_r2[k] = (int32_t)((uint32_t)s_lv_p[0][k] + (uint32_t)s_lv_p[1][k] + (uint32_t)s_lv_p[2][k]);
  }
  s_lv_ok = 1;
}

/* Which of control_levels' commands q is (0..2), 3 none. A macro: a function's argument would need
 * internal RAM the 8051 has no room for. */
#define LEVEL_OF(q) ((q) == s_lv_q[0] ? 0u : (q) == s_lv_q[1] ? 1u : (q) == s_lv_q[2] ? 2u : 3u)

/* refresh_r for a new command from control_levels' table: 1 if it holds the command and the two
 * before it, 0 (nothing changed) otherwise. */
static uint8_t level_r(void) {
  MCG_SLOW uint8_t k;
  MCG_SLOW uint8_t k1;
  MCG_SLOW uint8_t h;
  if (!s_lv_ok) {
    return 0;
  }
  k = (uint8_t)LEVEL_OF(s_r_q8);
  k1 = (uint8_t)LEVEL_OF(s_r1);
  h = (uint8_t)LEVEL_OF(s_r2);
  if (k > 1u || k1 > 2u || h > 2u) {
    return 0;
  }
  if (h == 2u) {
    h = (uint8_t)(4u + k1);
  } else if (k1 == 2u) {
    return 0;
  } else {
    h = (uint8_t)((uint8_t)(k1 << 1) | h);
  }
  g_ctl_r[0] = s_lv_r0[(uint8_t)(k << 3) | h];
  g_ctl_r[1] = s_lv_r1[(uint8_t)(k << 2) | k1];
  g_ctl_r[2] = s_lv_r2[k];
  g_ctl_r_k = 0;
  return 1;
}

/* The shadow set's settled R = sum_i c_i r (+ the bias in P mode), and its operands bp. */
static void next_r(void) {
  s_next_bp[0] = 0x8000u;
  s_next_bp[1] = 0x8000u;
  s_next_bp[2] = 0x8000u;
  s_next_r = 0;
  if (g_ctl_shadow.mode == MCG_MODE_P) {
    s_next_bp[0] = (uint16_t)((uint16_t)g_ctl_shadow.kp ^ 0x8000u);
    s_next_r = arith_mul16(g_ctl_shadow.kp, s_r_q8) + s_next_u_bias;
  } else if (g_ctl_shadow.mode != MCG_MODE_OPEN) {
    s_next_bp[0] = (uint16_t)((uint16_t)g_ctl_shadow.b0 ^ 0x8000u);
    s_next_bp[1] = (uint16_t)((uint16_t)g_ctl_shadow.b1 ^ 0x8000u);
    s_next_r = arith_mul16(g_ctl_shadow.b0, s_r_q8) + arith_mul16(g_ctl_shadow.b1, s_r_q8);
    if (g_ctl_shadow.mode == MCG_MODE_PID) {
      s_next_bp[2] = (uint16_t)((uint16_t)g_ctl_shadow.b2 ^ 0x8000u);
      s_next_r += arith_mul16(g_ctl_shadow.b2, s_r_q8);
    }
  }
}

void control_staged(uint8_t writer) {
  s_next_scale = (int16_t)(1 << g_ctl_shadow.coef_frac);
  s_next_u_min = scale_next(g_ctl_shadow.duty_min);
  s_next_u_max = scale_next(g_ctl_shadow.duty_max);
  s_next_u_bias = scale_next(g_ctl_shadow.duty_bias);
  next_r();
  if (!s_staged) {
    s_staged = writer;
  }
}

uint8_t control_owner(void) { return s_staged; }

/* The gains the mode uses, all zero: a closed-loop mode would hold its output where it is, or at the
 * bias, whatever the speed (the 3221 rpm runaway of a PI entered with gains never written). */
static uint8_t gains_missing(void) {
  if (g_ctl_shadow.mode == MCG_MODE_P) {
    return g_ctl_shadow.kp == 0;
  }
  if (g_ctl_shadow.mode == MCG_MODE_OPEN) {
    return 0;
  }
  return g_ctl_shadow.b0 == 0 && g_ctl_shadow.b1 == 0 &&
         (g_ctl_shadow.mode == MCG_MODE_PI || g_ctl_shadow.b2 == 0);
}

void control_discard(void) {
  g_ctl_shadow.mode = g_mode;
  g_ctl_shadow.kp = g_kp;
  g_ctl_shadow.b0 = g_b0;
  g_ctl_shadow.b1 = g_b1;
  g_ctl_shadow.b2 = g_b2;
  g_ctl_shadow.coef_frac = g_coef_frac;
  g_ctl_shadow.duty_bias = g_duty_bias;
  g_ctl_shadow.duty_min = g_duty_min;
  g_ctl_shadow.duty_max = g_duty_max;
  s_next_scale = s_scale;
  s_next_u_min = g_ctl_u_min;
  s_next_u_max = g_ctl_u_max;
  s_next_u_bias = s_u_bias;
  s_next_r = g_ctl_r[2];
  s_next_bp[0] = g_pid.bp[0];
  s_next_bp[1] = g_pid.bp[1];
  s_next_bp[2] = g_pid.bp[2];
  s_staged = 0;
}

uint8_t control_pending(void) {
  return (uint8_t)(g_ctl_shadow.mode != g_mode || g_ctl_shadow.kp != g_kp || g_ctl_shadow.b0 != g_b0 ||
                   g_ctl_shadow.b1 != g_b1 || g_ctl_shadow.b2 != g_b2 ||
                   g_ctl_shadow.coef_frac != g_coef_frac || g_ctl_shadow.duty_bias != g_duty_bias ||
                   g_ctl_shadow.duty_min != g_duty_min || g_ctl_shadow.duty_max != g_duty_max);
}

/* Runs between two ticks (the main loop runs the updates and the dispatch one after the other), so the
 * next update is the first with the new set and no update sees part of it. */
uint8_t control_commit(void) {
  int16_t out;
  if (gains_missing()) {
    control_discard();
    return MCG_ST_NO_GAINS;
  }
  if (g_ctl_shadow.duty_min > g_ctl_shadow.duty_max) {
    control_discard();
    return MCG_ST_LIMITS;
  }
  if (g_ctl_shadow.mode == MCG_MODE_OPEN && g_mode != MCG_MODE_OPEN) {
    g_duty_set = g_duty_out; /* open loop keeps the duty the controller left */
  }
  g_mode = g_ctl_shadow.mode;
  g_kp = g_ctl_shadow.kp;
  g_b0 = g_ctl_shadow.b0;
  g_b1 = g_ctl_shadow.b1;
  g_b2 = g_ctl_shadow.b2;
  g_coef_frac = g_ctl_shadow.coef_frac;
  g_duty_bias = g_ctl_shadow.duty_bias;
  g_duty_min = g_ctl_shadow.duty_min;
  g_duty_max = g_ctl_shadow.duty_max;
  s_lv_ok = 0; /* control_levels' table holds the old set's R */
  /* Bumpless: U[n-1] is the present output within the new limits, in the new format; the error
   * history (pulses, command) carries on, so PI and PID continue from the duty now driving the motor,
   * and open loop keeps it. */
  out = g_duty_out;
  if (out < g_duty_min) {
    out = g_duty_min;
  } else if (out > g_duty_max) {
    out = g_duty_max;
  }
  if (g_mode == MCG_MODE_OPEN) {
    if (g_duty_set < g_duty_min) {
      g_duty_set = g_duty_min;
    } else if (g_duty_set > g_duty_max) {
      g_duty_set = g_duty_max;
    }
  }
  /* What the set derives was computed as it was written: copied here, the commit and the next
   * update fit in one tick on the 8051. */
  g_ctl_shift = (uint8_t)(g_coef_frac + MCG_ERR_FRAC_BITS);
  s_scale = s_next_scale;
  g_ctl_u_min = s_next_u_min;
  g_ctl_u_max = s_next_u_max;
  s_u_bias = s_next_u_bias;
  g_ctl_u = scale_up(out);
  if (g_ctl_settle == 0) {
    g_pid.bp[0] = s_next_bp[0];
    g_pid.bp[1] = s_next_bp[1];
    g_pid.bp[2] = s_next_bp[2];
    g_ctl_r[2] = s_next_r;
    g_ctl_r[1] = g_ctl_r[2];
    g_ctl_r[0] = g_ctl_r[2];
    g_ctl_r_k = 0;
  } else {
    control_refresh(); /* the command history is still moving: R for each of the next ticks */
  }
  s_staged = 0;
  return MCG_ST_OK;
}

/* Pulses of the last MCG_SPEED_WINDOW_MS ticks, for rpm (display, register, not the controller). */
void speed_tick(uint8_t pulses) {
  g_counts_16ms = (uint16_t)(g_counts_16ms + pulses - s_window[s_window_pos]);
  s_window[s_window_pos] = pulses;
  s_window_pos = (uint8_t)((s_window_pos + 1u) & (MCG_SPEED_WINDOW_MS - 1u));
}

void control_settle(void) {
  s_r2 = s_r1;
  s_r1 = s_r_q8;
  --g_ctl_settle;
}
