/* arith.h: the controller's widened multiplies: 16 x 16 -> 32 bits signed, and the PID sum.
 *
 * C's (int32_t)a * b is exact everywhere, but SDCC turns it into a 32 x 32 multiply (__mullong);
 * the 8051 build links a MUL AB version instead (board/mcs51/arith_mcs51.c). arith_pid_sum is the
 * pulse part of the controller's sum (control.c), used by the C update (control_tick.c). */
#ifndef MCG_FIRMWARE_CORE_ARITH_H
#define MCG_FIRMWARE_CORE_ARITH_H

#include <stdint.h> /* int16_t, int32_t */

#include "compiler.h" /* MCG_MCS51 */

/* Operands of arith_pid_sum: bp[i] = b_i + 2^15 (offset binary of the signed coefficient) and
 * the pulse counts p[i] = p[n-i]. Directly addressed internal RAM on the 8051. */
typedef struct {
  uint16_t bp[3];
  uint8_t p[3];
} ArithPid;
extern ArithPid g_pid;

#if MCG_MCS51
int32_t arith_mul16(int16_t a, int16_t b);
/* arith_pid_sum has no 8051 version: the assembly control_tick does the same sum inline. */
#else
static inline int32_t arith_mul16(int16_t a, int16_t b) { return (int32_t)a * (int32_t)b; }

/* -256 sum_i b_i p[i] (mod 2^32), as 2^23 P - 256 T with T = sum_i bp[i] p[i] and P = sum_i p[i]:
 * b_i p = (bp[i] - 2^15) p, so only unsigned 16 x 8 products are needed. */
static inline int32_t arith_pid_sum(void) {
  uint32_t t = 0;
  uint32_t p = 0;
  int i;
  for (i = 0; i < 3; ++i) {
    t += (uint32_t)g_pid.bp[i] * g_pid.p[i];
    p += g_pid.p[i];
  }
  return (int32_t)((p << 23) - (t << 8));
}
#endif

#endif
