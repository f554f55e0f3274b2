/* board_ucsim.h: the SIM build for s51 (-t C517), whose 80C517 model lacks the 80515 peripherals.
 *
 * 12 MHz crystal. Timer 0 (mode 1, reloaded in its interrupt) gives the 1 ms tick; Timer 1 (mode 2,
 * SMOD = 1, TH1 = 0xF9) clocks the UART (8929 baud, -7 %: s51 does not time the line anyway).
 * No encoder and no PWM pins exist in the model, so this layer closes the loop itself: a test
 * encoder counts duty / SIM_PULSES_DIVISOR pulses per tick (duty 400 -> 10 pulses/ms = 293 rpm),
 * and the I/O the test harness looks at lives in external RAM at SIM_IO_XADDR:
 *   +0..1  duty written to the PWM (i16 LE)       +2  clutch (0/1)   +3  load relay (0/1)
 *   +4     key held (written by the harness; 0xFF = none)
 *   +5     number of keys queued at +0x30 (written last): each is then presented as held for one
 *          keypad sample and released for the next, whatever the simulation speed
 *   +0x10  LCD row 0 (16 characters)               +0x20  LCD row 1
 *   +0x30  the key queue (up to 16 keys) */
#ifndef MCG_FIRMWARE_BOARD_UCSIM_BOARD_UCSIM_H
#define MCG_FIRMWARE_BOARD_UCSIM_BOARD_UCSIM_H

#include "compiler.h" /* MCG_ISR */

#define SIM_IO_XADDR 0x9F00u
#define SIM_KEY_QUEUE 0x30u
#define SIM_KEY_QUEUE_MAX 16u
#define SIM_PULSES_DIVISOR 40
#define SIM_T0_RELOAD_H 0xFCu /* 65536 - 1000 = 0xFC18, plus 8 cycles spent before the reload */
#define SIM_T0_RELOAD_L 0x20u

void board_tick_isr(void) MCG_ISR(1);

#endif
