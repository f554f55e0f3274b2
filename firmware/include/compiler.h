/* compiler.h: the only place SDCC's 8051 keywords appear; on any other compiler they vanish.
 *
 * The core is written in C99 that both gcc (host layer, unit tests, mcg-sim --board) and SDCC
 * (mcs51, small model) accept. Memory-space and interrupt qualifiers go through these macros. */
#ifndef MCG_FIRMWARE_INCLUDE_COMPILER_H
#define MCG_FIRMWARE_INCLUDE_COMPILER_H

#if defined(__SDCC_mcs51)
#define MCG_MCS51 1
#define MCG_XDATA __xdata           /* external RAM (MOVX) */
#define MCG_CODE __code             /* program memory (MOVC), read-only tables */
#define MCG_AT(addr) __at(addr)     /* absolute address */
#define MCG_ISR(vec) __interrupt(vec)
#define MCG_USING(bank) __using(bank)
#else
#define MCG_MCS51 0
#define MCG_XDATA
#define MCG_CODE const
#define MCG_AT(addr)
#define MCG_ISR(vec)
#define MCG_USING(bank)
#endif

#endif
