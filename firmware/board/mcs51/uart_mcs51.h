/* uart_mcs51.h: the 8051 serial port as interrupt-driven rings (shared by the c515 and ucsim layers).
 *
 * The serial interrupt only moves bytes between SBUF and the rings; hal_uart_* (hal.h) run on the
 * main loop. Mode 1, 8 data bits (SCON = 0x50): all eight bits of every byte travel, where the
 * report's board lost the eighth. The board layer sets the baud rate generator, then calls
 * uart_init(). This header must be included by the file holding main(), as SDCC requires for ISRs. */
#ifndef MCG_FIRMWARE_BOARD_MCS51_UART_MCS51_H
#define MCG_FIRMWARE_BOARD_MCS51_UART_MCS51_H

#include "compiler.h" /* MCG_ISR */

#define UART_RX_RING 64u  /* power of two */
#define UART_TX_RING 128u /* power of two; holds the largest frame (69 bytes) */

void uart_init(void);
void uart_isr(void) MCG_ISR(4);

#endif
