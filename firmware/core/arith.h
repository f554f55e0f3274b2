/* arith.h: the widened multiply of the controller, 16 x 16 -> 32 bits signed.
 *
 * C's (int32_t)a * b is exact everywhere, but SDCC turns it into a 32 x 32 multiply (__mullong);
 * the 8051 build links a MUL AB version instead (board/mcs51/arith_mcs51.c). */
#ifndef MCG_FIRMWARE_CORE_ARITH_H
#define MCG_FIRMWARE_CORE_ARITH_H

#include <stdint.h> /* int16_t, int32_t */

#include "compiler.h" /* MCG_MCS51 */

#if MCG_MCS51
int32_t arith_mul16(int16_t a, int16_t b);
#else
static inline int32_t arith_mul16(int16_t a, int16_t b)
{
  return (int32_t)a * (int32_t)b;
}
#endif

#endif
