/* control_tick.c: the 1 ms control update in C, the reference for every build.
 *
 * The 8051 build links board/mcs51/control_tick_mcs51.c instead, the same steps in assembly; the
 * ucsim test checks that both give the same duty, update by update. The equations are in
 * control.c; the state lives there too (g_ctl_*). */
#include "arith.h" /* arith_pid_sum */
#include "core.h"
#include "hal.h" /* hal_pwm_write */

/* (U + 2^(s-1)) >> s with s = F + 8, rounded half up. */
static int16_t output_of(int32_t u) {
  return (int16_t)((u + ((int32_t)1 << (g_ctl_shift - 1u))) >> g_ctl_shift);
}

void control_tick(uint8_t pulses) {
  int16_t out;
  int32_t u;

  g_pid.p[2] = g_pid.p[1];
  g_pid.p[1] = g_pid.p[0];
  g_pid.p[0] = pulses > g_ctl_p_hi ? g_ctl_p_hi : pulses;

  if (g_mode == MCG_MODE_OPEN) {
    g_saturated = 0;
    out = g_duty_set;
  } else {
    /* U = (PI, PID: U[n-1]) + R[n] + sum; mod 2^32, the exact result is in range (control.c). */
    u = (int32_t)((uint32_t)g_ctl_r[g_ctl_r_k] + (uint32_t)arith_pid_sum());
    if (g_mode != MCG_MODE_P) {
      u = (int32_t)((uint32_t)u + (uint32_t)g_ctl_u);
    }
    if (g_ctl_r_k < 2u) {
      ++g_ctl_r_k;
    }
    g_saturated = 0;
    if (u > g_ctl_u_max) {
      u = g_ctl_u_max;
      g_saturated = 1;
    } else if (u < g_ctl_u_min) {
      u = g_ctl_u_min;
      g_saturated = 1;
    }
    if (g_mode != MCG_MODE_P) {
      g_ctl_u = u;
    }
    out = output_of(u);
  }
  g_duty_out = out;
  if (g_ctl_settle) {
    control_settle();
  }
  hal_pwm_write(out);
}
