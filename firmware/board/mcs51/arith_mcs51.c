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

/* arith_pid_sum: -256 sum_i b_i p[i] (mod 2^32) = 2^23 P - 256 T, T = sum_i bp[i] p[i], P = sum_i p[i]
 * (arith.h). Each bp[i] p[i] is two MUL AB (bpL p, bpH p << 8) into T in R2 (low), R3, R4 (high);
 * P in R0 (low), R1. g_pid: bp[0..2] at +0..+5 (little-endian), p[0..2] at +6..+8. */
int32_t arith_pid_sum(void) __naked
{
  __asm
    mov a, (_g_pid + 6)         ; p0 bp0L
    mov b, (_g_pid + 0)
    mul ab
    mov r2, a
    mov r3, b
    mov a, (_g_pid + 6)         ; p0 bp0H
    mov b, (_g_pid + 1)
    mul ab
    add a, r3
    mov r3, a
    clr a
    addc a, b
    mov r4, a
    mov a, (_g_pid + 7)         ; p1 bp1L
    mov b, (_g_pid + 2)
    mul ab
    add a, r2
    mov r2, a
    mov a, b
    addc a, r3
    mov r3, a
    clr a
    addc a, r4
    mov r4, a
    mov a, (_g_pid + 7)         ; p1 bp1H
    mov b, (_g_pid + 3)
    mul ab
    add a, r3
    mov r3, a
    mov a, b
    addc a, r4
    mov r4, a
    mov a, (_g_pid + 8)         ; p2 bp2L
    mov b, (_g_pid + 4)
    mul ab
    add a, r2
    mov r2, a
    mov a, b
    addc a, r3
    mov r3, a
    clr a
    addc a, r4
    mov r4, a
    mov a, (_g_pid + 8)         ; p2 bp2H
    mov b, (_g_pid + 5)
    mul ab
    add a, r3
    mov r3, a
    mov a, b
    addc a, r4
    mov r4, a
    mov a, (_g_pid + 6)         ; P = p0 + p1 + p2 in R1:R0
    add a, (_g_pid + 7)
    mov r0, a
    clr a
    addc a, #0
    mov r1, a
    mov a, r0
    add a, (_g_pid + 8)
    mov r0, a
    clr a
    addc a, r1
    mov r1, a
    mov a, r0                   ; 2^23 P: byte 2 = (P0 & 1) << 7 in R6
    anl a, #0x01
    rr a
    mov r6, a
    mov a, r1                   ; byte 3 = (P1 << 7) | (P0 >> 1) in R7
    rrc a
    mov a, r0
    rrc a
    mov r7, a
    clr c                       ; minus T << 8: bytes 1..3
    clr a
    subb a, r2
    mov dph, a
    mov a, r6
    subb a, r3
    mov b, a
    mov a, r7
    subb a, r4
    mov dpl, #0x00
    ret
  __endasm;
}
