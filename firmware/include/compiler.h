/* compiler.h: the only place SDCC's 8051 keywords appear; on any other compiler they vanish.
 *
 * The core is written in C99 that both gcc (host layer, unit tests, mcg-sim --board) and SDCC
 * (mcs51, small model) accept. Memory-space and interrupt qualifiers go through these macros. */
#ifndef MCG_FIRMWARE_INCLUDE_COMPILER_H
#define MCG_FIRMWARE_INCLUDE_COMPILER_H

#if defined(__SDCC_mcs51)
#define MCG_MCS51 1
#define MCG_XDATA __xdata       /* external RAM (MOVX) */
#define MCG_CODE __code         /* program memory (MOVC), read-only tables */
#define MCG_IDATA __idata       /* upper internal RAM (indirect) */
#define MCG_AT(addr) __at(addr) /* absolute address */
#define MCG_ISR(vec) __interrupt(vec)
#define MCG_USING(bank) __using(bank)
#define MCG_REENTRANT __reentrant /* parameters and locals on the stack (upper internal RAM) */
#else
#define MCG_MCS51 0
#define MCG_XDATA
#define MCG_CODE const
#define MCG_IDATA
#define MCG_AT(addr)
#define MCG_ISR(vec)
#define MCG_USING(bank)
#define MCG_REENTRANT
#endif

/* Locals of slow-path functions (menu, parser): kept in external RAM on the 8051, so that the
 * 128 bytes of directly addressed internal RAM stay with the control path. Only in functions that
 * are neither recursive nor called from an interrupt (SDCC locals are static). */
#define MCG_SLOW MCG_XDATA

#endif
