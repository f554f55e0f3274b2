/* control_tick_mcs51.c: control_tick (core.h) in 8051 assembly, step for step the C reference
 * core/control_tick.c, which the host builds use. The ucsim test runs both on the same pulses and
 * requires the same duty from every update.
 *
 * pulses in DPL. Register use (bank 0, all free at a call): R4..R7 the accumulator U (LSB first),
 * R1..R3 the pulse products T, R2:R3 the duty on the way out; PSW.F0 marks P mode. The operands are in directly
 * addressed RAM: g_pid (arith.h: bp[0..2] at +0..+5, p[0..2] at +6..+8) and the g_ctl_* state of
 * control.c; the R queue g_ctl_r is in indirectly addressed RAM. Steps:
 *   p history, p[0] = min(pulses, p_hi)
 *   open loop: duty = duty_set
 *   else U = R[k] (+ U[n-1] in PI, PID) - 256 T + 2^23 P   with T = sum bp[i] p[i], P = sum p[i]
 *        saturate U to [U_min, U_max] (flag), keep it (PI, PID), duty = (U + 2^(s-1)) >> s
 *   duty_out = duty; command history step if unsettled; tail call hal_pwm_write(duty). */
#include "arith.h" /* g_pid */
#include "core.h"  /* control_tick and the g_ctl_* state */

void control_tick(uint8_t pulses) __naked
{
  (void)pulses;
  __asm
    mov a, dpl
    mov r7, a
    mov (_g_pid + 8), (_g_pid + 7)
    mov (_g_pid + 7), (_g_pid + 6)
    clr c
    subb a, _g_ctl_p_hi
    mov a, r7
    jc 00001$
    mov a, _g_ctl_p_hi
00001$:
    mov (_g_pid + 6), a
    mov a, _g_mode
    jnz 00010$
    mov _g_saturated, #0x00
    mov r2, _g_duty_set
    mov r3, (_g_duty_set + 1)
    ljmp 00090$

00010$:                         ; F0 = P mode (no U[n-1])
    clr f0
    cjne a, #0x01, 00009$
    setb f0
00009$:                         ; U = R[k], k advances to 2 and stays
    mov a, _g_ctl_r_k
    cjne a, #0x02, 00008$
    sjmp 00007$
00008$:
    inc _g_ctl_r_k
00007$:
    rl a
    rl a
    add a, #_g_ctl_r
    mov r0, a
    mov ar4, @r0
    inc r0
    mov ar5, @r0
    inc r0
    mov ar6, @r0
    inc r0
    mov ar7, @r0
    jb f0, 00012$               ; PI, PID: U += U[n-1]
    mov a, r4
    add a, _g_ctl_u
    mov r4, a
    mov a, r5
    addc a, (_g_ctl_u + 1)
    mov r5, a
    mov a, r6
    addc a, (_g_ctl_u + 2)
    mov r6, a
    mov a, r7
    addc a, (_g_ctl_u + 3)
    mov r7, a
00012$:                         ; T = bp0 p0 + bp1 p1 + bp2 p2 in R3:R2:R1
    mov a, (_g_pid + 6)
    mov b, (_g_pid + 0)
    mul ab
    mov r1, a
    mov r2, b
    mov a, (_g_pid + 6)
    mov b, (_g_pid + 1)
    mul ab
    add a, r2
    mov r2, a
    clr a
    addc a, b
    mov r3, a
    mov a, (_g_pid + 7)
    mov b, (_g_pid + 2)
    mul ab
    add a, r1
    mov r1, a
    mov a, b
    addc a, r2
    mov r2, a
    clr a
    addc a, r3
    mov r3, a
    mov a, (_g_pid + 7)
    mov b, (_g_pid + 3)
    mul ab
    add a, r2
    mov r2, a
    mov a, b
    addc a, r3
    mov r3, a
    mov a, (_g_pid + 8)
    mov b, (_g_pid + 4)
    mul ab
    add a, r1
    mov r1, a
    mov a, b
    addc a, r2
    mov r2, a
    clr a
    addc a, r3
    mov r3, a
    mov a, (_g_pid + 8)
    mov b, (_g_pid + 5)
    mul ab
    add a, r2
    mov r2, a
    mov a, b
    addc a, r3
    mov r3, a
    clr c                       ; U -= T << 8
    mov a, r5
    subb a, r1
    mov r5, a
    mov a, r6
    subb a, r2
    mov r6, a
    mov a, r7
    subb a, r3
    mov r7, a
    mov a, (_g_pid + 6)         ; P = p0 + p1 + p2 (each <= 85: one byte)
    add a, (_g_pid + 7)
    add a, (_g_pid + 8)
    clr c                       ; U += P << 23: byte 3 += P >> 1, byte 2 += (P & 1) << 7
    rrc a
    mov r2, a
    clr a
    rrc a
    add a, r6
    mov r6, a
    mov a, r2
    addc a, r7
    mov r7, a

    mov a, r7                   ; limits: the top bytes decide unless equal (signed: ^ 0x80)
    xrl a, #0x80
    mov r1, a
    mov a, (_g_ctl_u_max + 3)
    xrl a, #0x80
    clr c
    subb a, r1
    jc 00025$                   ; U > U_max
    jnz 00022$                  ; U < U_max
    clr c                       ; same top byte: the whole of U_max - U
    mov a, _g_ctl_u_max
    subb a, r4
    mov a, (_g_ctl_u_max + 1)
    subb a, r5
    mov a, (_g_ctl_u_max + 2)
    subb a, r6
    mov a, (_g_ctl_u_max + 3)
    subb a, r7
    jnc 00022$
00025$:
    mov r4, _g_ctl_u_max
    mov r5, (_g_ctl_u_max + 1)
    mov r6, (_g_ctl_u_max + 2)
    mov r7, (_g_ctl_u_max + 3)
    mov _g_saturated, #0x01
    sjmp 00030$
00022$:
    mov a, (_g_ctl_u_min + 3)
    xrl a, #0x80
    clr c
    subb a, r1
    jc 00021$                   ; U > U_min
    jnz 00026$                  ; U < U_min
    clr c                       ; same top byte: the whole of U - U_min
    mov a, r4
    subb a, _g_ctl_u_min
    mov a, r5
    subb a, (_g_ctl_u_min + 1)
    mov a, r6
    subb a, (_g_ctl_u_min + 2)
    mov a, r7
    subb a, (_g_ctl_u_min + 3)
    jnc 00021$
00026$:
    mov r4, _g_ctl_u_min
    mov r5, (_g_ctl_u_min + 1)
    mov r6, (_g_ctl_u_min + 2)
    mov r7, (_g_ctl_u_min + 3)
    mov _g_saturated, #0x01
    sjmp 00030$
00021$:
    mov _g_saturated, #0x00
00030$:                         ; PI, PID keep U
    jb f0, 00031$
    mov _g_ctl_u, r4
    mov (_g_ctl_u + 1), r5
    mov (_g_ctl_u + 2), r6
    mov (_g_ctl_u + 3), r7
00031$:                         ; duty = (U + 2^(s-1)) >> s
    mov a, _g_ctl_shift
    cjne a, #16, 00040$
    mov a, r5                   ; s = 16 (F = 8): + 2^15, then the two high bytes
    add a, #0x80
    clr a
    addc a, r6
    mov r2, a
    clr a
    addc a, r7
    mov r3, a
    sjmp 00090$
00040$:                         ; any s: floor((floor(U / 2^(s-1)) + 1) / 2)
    dec a
    mov r1, a
00041$:                         ; whole bytes first
    mov a, r1
    add a, #0xF8
    jnc 00042$
    mov r1, a
    mov ar4, r5
    mov ar5, r6
    mov ar6, r7
    mov a, r7
    rlc a
    clr a
    subb a, #0x00
    mov r7, a
    sjmp 00041$
00042$:
    mov a, r1
    jz 00044$
00043$:                         ; then single bits, arithmetic
    mov a, r7
    mov c, acc.7
    rrc a
    mov r7, a
    mov a, r6
    rrc a
    mov r6, a
    mov a, r5
    rrc a
    mov r5, a
    mov a, r4
    rrc a
    mov r4, a
    djnz r1, 00043$
00044$:
    mov a, r4
    add a, #0x01
    mov r4, a
    clr a
    addc a, r5
    mov r5, a
    clr a
    addc a, r6
    mov r6, a
    clr a
    addc a, r7
    mov c, acc.7
    rrc a
    mov a, r6
    rrc a
    mov a, r5
    rrc a
    mov r3, a
    mov a, r4
    rrc a
    mov r2, a

00090$:
    mov _g_duty_out, r2
    mov (_g_duty_out + 1), r3
    mov a, _g_ctl_settle
    jz 00091$
    push ar2
    push ar3
    lcall _control_settle
    pop ar3
    pop ar2
00091$:
    mov dpl, r2
    mov dph, r3
    ljmp _hal_pwm_write
  __endasm;
}
