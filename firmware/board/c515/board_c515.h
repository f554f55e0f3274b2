/* board_c515.h: every pin, address and timer constant of the EMAC SAB 80C515 board, in one place.
 *
 * Clock 12 MHz: machine cycle 1 us.
 * Tick + PWM: Timer 2 in reload mode (T2CON = 0x11: f/12, reload on overflow) from CRC = 0xFC18
 *   overflows every 1000 us; its interrupt (TF2 in IRCON, vector 0x2B) is the 1 ms control tick.
 *   Compare register CC1 in compare mode 0 drives P1.1 high from the match to the overflow, so
 *   CC1 = 0x10000 - duty_us gives duty_us / 1000 in 1000 steps of 0.1 % (spec: 500 or more).
 * Encoder: Timer 0 as a 16-bit counter of the encoder pulses on T0 (P3.4), read at each tick.
 * UART: 9600 baud from the internal baud generator (ADCON.BD = 1, PCON.SMOD = 1 at 12 MHz).
 * Outputs on port 4: motor direction (to the XOR gate before the H-bridge), clutch transistor
 *   (2N2222), load relay.
 * LCD (HD44780-type, 2 x 16) and keypad (4 x 4 through a key encoder with data-available flag)
 *   are memory-mapped in external data space; the addresses below are the lab board's decoding
 *   and must match the board's jumpers. */
#ifndef MCG_FIRMWARE_BOARD_C515_BOARD_C515_H
#define MCG_FIRMWARE_BOARD_C515_BOARD_C515_H

#include "compiler.h" /* MCG_ISR */

#define C515_T2CON 0x11u       /* T2I0 (f/12) | T2R1 (reload mode 0) */
#define C515_T2_RELOAD 0xFC18u /* 65536 - 1000 */
#define C515_CCEN_CC1 0x08u    /* COCAH1:COCAL1 = 10, compare enabled on CC1 (COCAL1 stays 0) */
#define C515_CCEN_CC1_MASK 0x0Cu

#define C515_P4_DIR 0x01u    /* P4.0: motor direction, 1 = reverse */
#define C515_P4_CLUTCH 0x02u /* P4.1: clutch transistor, 1 = engaged */
#define C515_P4_LOAD 0x04u   /* P4.2: generator load relay, 1 = closed */

#define C515_LCD_CMD_XADDR 0xFF80u  /* HD44780 instruction register (write), busy flag (read) */
#define C515_LCD_DATA_XADDR 0xFF81u /* HD44780 data register */
#define C515_LCD_BUSY 0x80u
#define C515_LCD_BUSY_POLLS 200u /* give up waiting after this many polls: never hang */
#define C515_LCD_POWER_UP_MS 20u /* wait before the first LCD command (HD44780: > 15 ms) */
#define C515_KEY_XADDR 0xFFC0u   /* key encoder: bits 0..3 key code, bit 7 data available */
#define C515_KEY_AVAILABLE 0x80u

/* Reads the 16-bit encoder count of Timer 0 while it runs: re-read until the high byte is stable.
 * A macro, not a function: it runs inside the tick interrupt (no calls there). */
#define C515_ENCODER_READ(hi, lo) \
  do {                            \
    (hi) = TH0;                   \
    (lo) = TL0;                   \
  } while ((hi) != TH0)

void board_tick_isr(void) MCG_ISR(5);

#endif
