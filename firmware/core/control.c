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
uint8_t g_ctl_p_hi;
int32_t MCG_IDATA g_ctl_r[3];
uint8_t g_ctl_r_k;
int32_t g_ctl_u;
int32_t g_ctl_u_min, g_ctl_u_max;
uint8_t g_ctl_shift;
uint8_t g_ctl_settle;

/* x * 2^shift without shifting a negative value (undefined in C). */
static int32_t scale_up(int16_t x) { return (int32_t)x * ((int32_t)1 << g_ctl_shift); }

static void rescale(void) {
  g_ctl_shift = (uint8_t)(g_coef_frac + MCG_ERR_FRAC_BITS);
  g_ctl_u_min = scale_up(g_duty_min);
  g_ctl_u_max = scale_up(g_duty_max);
  s_u_bias = scale_up(g_duty_bias);
  g_ctl_u = scale_up(g_duty_out);
}

int16_t control_rpm_to_q8(int16_t rpm) {
  /* 2048 * 256 = 524288 counts * 2^8 per revolution; 60000 ms per minute. */
  int32_t num = (int32_t)rpm * 524288L;
  if (num >= 0) {
    return (int16_t)((num + 30000L) / 60000L);
  }
  return (int16_t) - ((-num + 30000L) / 60000L);
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
  for (i = 0; i < 3; ++i) {
    g_pid.p[i] = 0;
  }
  g_ctl_p_hi = 85;
  rescale();
  control_refresh();
}

void control_set_rpm_cmd(int16_t rpm) {
  int16_t hi;
  s_r_q8 = control_rpm_to_q8(rpm);
  hi = (int16_t)((s_r_q8 + MCG_ERR_LIMIT) >> 8);
  /* 56 at 720 rpm; never above 85, so that three pulse counts sum to at most 255 */
  g_ctl_p_hi = hi > 85 ? 85u : (uint8_t)hi;
  g_ctl_settle = 2; /* the tick shifts the command history until it holds the new one twice */
  control_refresh();
}

/* The coefficients of the active mode, as R and the operands of arith_pid_sum use them. */
static void active_coefs(int16_t* c0, int16_t* c1, int16_t* c2) {
  *c0 = 0;
  *c1 = 0;
  *c2 = 0;
  if (g_mode == MCG_MODE_P) {
    *c0 = g_kp;
  } else if (g_mode == MCG_MODE_PI || g_mode == MCG_MODE_PID) {
    *c0 = g_b0;
    *c1 = g_b1;
    *c2 = g_mode == MCG_MODE_PID ? g_b2 : 0;
  }
}

void control_refresh(void) {
  MCG_SLOW int16_t c0;
  MCG_SLOW int16_t c1;
  MCG_SLOW int16_t c2;
  MCG_SLOW int32_t now0;
  active_coefs(&c0, &c1, &c2);
  g_pid.bp[0] = (uint16_t)((uint16_t)c0 ^ 0x8000u);
  g_pid.bp[1] = (uint16_t)((uint16_t)c1 ^ 0x8000u);
  g_pid.bp[2] = (uint16_t)((uint16_t)c2 ^ 0x8000u);
  now0 = arith_mul16(c0, s_r_q8);
  g_ctl_r[0] = now0 + arith_mul16(c1, s_r1) + arith_mul16(c2, s_r2);
  g_ctl_r[1] = now0 + arith_mul16(c1, s_r_q8) + arith_mul16(c2, s_r1);
  g_ctl_r[2] = now0 + arith_mul16(c1, s_r_q8) + arith_mul16(c2, s_r_q8);
  if (g_mode == MCG_MODE_P) {
    g_ctl_r[0] += s_u_bias;
    g_ctl_r[1] += s_u_bias;
    g_ctl_r[2] += s_u_bias;
  }
  g_ctl_r_k = 0;
}

void control_set_mode(uint8_t mode) {
  (void)mode;
  g_ctl_u = scale_up(g_duty_out); /* bumpless: the integrator starts from the present output */
  control_refresh();
}

void control_set_coef_frac(uint8_t frac_bits) {
  g_coef_frac = frac_bits;
  rescale();
  control_refresh();
}

void control_set_limits(int16_t duty_min, int16_t duty_max) {
  g_duty_min = duty_min;
  g_duty_max = duty_max;
  rescale();
  if (g_ctl_u > g_ctl_u_max) {
    g_ctl_u = g_ctl_u_max;
  } else if (g_ctl_u < g_ctl_u_min) {
    g_ctl_u = g_ctl_u_min;
  }
}

void control_set_bias(int16_t duty_bias) {
  g_duty_bias = duty_bias;
  s_u_bias = scale_up(duty_bias);
  control_refresh();
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
