/* arith_mcs51.c: arith_mul16 for the 8051, four MUL AB partial products and a sign correction.
 *
 * SDCC has no 16 x 16 -> 32 multiply: (int32_t)a * b calls the 32 x 32 __mullong. Here, with
 * a = aH:aL and b = bH:bL taken as unsigned,
 *   a * b = aL bL + 2^8 (aL bH + aH bL) + 2^16 aH bH,
 * and for signed operands 2^16 b is subtracted if a < 0 and 2^16 a if b < 0 (mod 2^32).
 * Calling convention (SDCC small model): a in DPL:DPH, b in arith_mul16_PARM_2, result in
 * DPL, DPH, B, A (LSB first); R4..R7 are free to use. */
#include "arith.h"

int32_t arith_mul16(int16_t a, int16_t b) __naked
{
  (void)a;
  (void)b;
  __asm
    mov a, dpl
    mov b, _arith_mul16_PARM_2
    mul ab                      ; aL bL
    mov r4, a
    mov r5, b
    mov a, dph
    mov b, (_arith_mul16_PARM_2 + 1)
    mul ab                      ; aH bH
    mov r6, a
    mov r7, b
    mov a, dpl
    mov b, (_arith_mul16_PARM_2 + 1)
    mul ab                      ; aL bH
    add a, r5
    mov r5, a
    mov a, b
    addc a, r6
    mov r6, a
    clr a
    addc a, r7
    mov r7, a
    mov a, dph
    mov b, _arith_mul16_PARM_2
    mul ab                      ; aH bL
    add a, r5
    mov r5, a
    mov a, b
    addc a, r6
    mov r6, a
    clr a
    addc a, r7
    mov r7, a
    mov a, dph
    jnb acc.7, 00001$           ; a < 0: subtract 2^16 b
    clr c
    mov a, r6
    subb a, _arith_mul16_PARM_2
    mov r6, a
    mov a, r7
    subb a, (_arith_mul16_PARM_2 + 1)
    mov r7, a
00001$:
    mov a, (_arith_mul16_PARM_2 + 1)
    jnb acc.7, 00002$           ; b < 0: subtract 2^16 a
    clr c
    mov a, r6
    subb a, dpl
    mov r6, a
    mov a, r7
    subb a, dph
    mov r7, a
00002$:
    mov dpl, r4
    mov dph, r5
    mov b, r6
    mov a, r7
    ret
  __endasm;
}
