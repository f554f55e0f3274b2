/* control.c: encoder speed over a 16 ms window and the 1 ms P / PI / PID controller in fixed point.
 *
 * Error, Q8 pulses per tick, saturated to +-MCG_ERR_LIMIT:
 *   e[n] = r - 256 * p[n],   r = rpm_cmd * 2048 * 256 / 60000 (rounded),  p[n] = pulses in tick n
 * Output u in 1/1000 duty, held in an int32 accumulator U in Q(F + 8), F = g_coef_frac:
 *   P:    U[n] = bias * 2^(F+8) + Kp e[n]
 *   PI:   U[n] = sat(U[n-1] + b0 e[n] + b1 e[n-1])
 *   PID:  U[n] = sat(U[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2])
 *   u[n] = sat((U[n] + 2^(F+7)) >> (F+8))   (round half up)
 * sat() limits to [duty_min, duty_max] * 2^(F+8): the incremental form stops integrating at the
 * limit (anti-windup). Each product is 16 x 16 -> 32 bits; |coef| <= 2^15 and |e| <= 2^13 bound every
 * product by 2^28 and, with |U| <= 1000 * 2^20, the sum stays below 2^31 for F <= 12: no overflow.
 *
 * Speed: a 16 ms window gives rpm = c * 60000 / (2048 * 16) = c * 1875 / 1024 with c the pulses in
 * the window. One pulse more or less (window phase) is 1.83 rpm, rounding adds 0.5 rpm: +-2.4 rpm,
 * inside the required +-5 rpm (the report's +-10 rpm corresponds to a 3 ms window). */
#include "core.h"

#include "arith.h" /* arith_mul16 */
#include "hal.h"   /* hal_pwm_write */

int16_t g_kp, g_b0, g_b1, g_b2;
uint8_t g_coef_frac;
int16_t MCG_XDATA g_duty_min, g_duty_max, g_duty_bias;
int16_t g_duty_out;
uint8_t g_saturated;
uint16_t g_counts_16ms;

static uint8_t MCG_IDATA s_window[MCG_SPEED_WINDOW_MS]; /* pulses per tick, ring */
static uint8_t s_window_pos;
static int16_t s_r_q8;                /* command, Q8 pulses per tick */
static int16_t s_e1, s_e2;            /* e[n-1], e[n-2] */
static int32_t s_u;                   /* U, Q(F+8) duty */
static int32_t s_u_min, s_u_max;      /* limits in Q(F+8) */
static MCG_XDATA int32_t s_u_bias;              /* P-mode bias in Q(F+8) */
static int32_t s_u_half;              /* 2^(F+7), rounding */
static uint8_t s_shift;               /* F + 8 */

/* x * 2^shift without shifting a negative value (undefined in C). */
static int32_t scale_up(int16_t x)
{
  return (int32_t)x * ((int32_t)1 << s_shift);
}

static int16_t output_of(int32_t u)
{
  return (int16_t)((u + s_u_half) >> s_shift);
}

static void rescale(void)
{
  s_shift = (uint8_t)(g_coef_frac + MCG_ERR_FRAC_BITS);
  s_u_half = (int32_t)1 << (s_shift - 1);
  s_u_min = scale_up(g_duty_min);
  s_u_max = scale_up(g_duty_max);
  s_u_bias = scale_up(g_duty_bias);
  s_u = scale_up(g_duty_out);
}

int16_t control_rpm_to_q8(int16_t rpm)
{
  /* 2048 * 256 = 524288 counts * 2^8 per revolution; 60000 ms per minute. */
  int32_t num = (int32_t)rpm * 524288L;
  if (num >= 0) {
    return (int16_t)((num + 30000L) / 60000L);
  }
  return (int16_t)-((-num + 30000L) / 60000L);
}

int16_t control_rpm(void)
{
  return (int16_t)(((uint32_t)g_counts_16ms * MCG_RPM_PER_WINDOW_NUM + MCG_RPM_PER_WINDOW_DEN / 2u) /
                   MCG_RPM_PER_WINDOW_DEN);
}

void control_init(void)
{
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
  g_coef_frac = 8;
  g_duty_min = 0;
  g_duty_max = MCG_DUTY_FULL;
  g_duty_bias = 0;
  g_duty_out = 0;
  g_saturated = 0;
  s_e1 = 0;
  s_e2 = 0;
  s_r_q8 = 0;
  rescale();
}

void control_set_rpm_cmd(int16_t rpm)
{
  s_r_q8 = control_rpm_to_q8(rpm);
}

void control_set_mode(uint8_t mode)
{
  (void)mode;
  s_u = scale_up(g_duty_out); /* bumpless: the integrator starts from the present output */
}

void control_set_coef_frac(uint8_t frac_bits)
{
  g_coef_frac = frac_bits;
  rescale();
}

void control_set_limits(int16_t duty_min, int16_t duty_max)
{
  g_duty_min = duty_min;
  g_duty_max = duty_max;
  rescale();
  if (s_u > s_u_max) {
    s_u = s_u_max;
  } else if (s_u < s_u_min) {
    s_u = s_u_min;
  }
}

void control_set_bias(int16_t duty_bias)
{
  g_duty_bias = duty_bias;
  s_u_bias = scale_up(duty_bias);
}

/* Limits u to [U_min, U_max] and records whether it had to. */
static int32_t saturate(int32_t u)
{
  if (u > s_u_max) {
    g_saturated = 1;
    return s_u_max;
  }
  if (u < s_u_min) {
    g_saturated = 1;
    return s_u_min;
  }
  g_saturated = 0;
  return u;
}

void control_tick(uint8_t pulses)
{
  int16_t e;
  int16_t out;

  g_counts_16ms = (uint16_t)(g_counts_16ms + pulses - s_window[s_window_pos]);
  s_window[s_window_pos] = pulses;
  s_window_pos = (uint8_t)((s_window_pos + 1u) & (MCG_SPEED_WINDOW_MS - 1u));

  if (pulses >= 128u) {
    e = -MCG_ERR_LIMIT;
  } else {
    e = (int16_t)(s_r_q8 - (int16_t)((uint16_t)pulses << 8));
    if (e > MCG_ERR_LIMIT) {
      e = MCG_ERR_LIMIT;
    } else if (e < -MCG_ERR_LIMIT) {
      e = -MCG_ERR_LIMIT;
    }
  }

  switch (g_mode) {
  case MCG_MODE_P:
    out = output_of(saturate(s_u_bias + arith_mul16(g_kp, e)));
    break;
  case MCG_MODE_PI:
    s_u = saturate(s_u + arith_mul16(g_b0, e) + arith_mul16(g_b1, s_e1));
    out = output_of(s_u);
    break;
  case MCG_MODE_PID:
    s_u = saturate(s_u + arith_mul16(g_b0, e) + arith_mul16(g_b1, s_e1) + arith_mul16(g_b2, s_e2));
    out = output_of(s_u);
    break;
  default:
    g_saturated = 0;
    out = g_duty_set;
    break;
  }
  s_e2 = s_e1;
  s_e1 = e;
  g_duty_out = out;
  hal_pwm_write(out);
}
