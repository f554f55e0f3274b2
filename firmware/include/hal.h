/* hal.h: the hardware seam. The core calls only these functions; each board layer implements them.
 *
 *   board/c515/   SAB 80C515 on the EMAC board (Timer 2 compare PWM, Timer 0 encoder counter, BD baud)
 *   board/ucsim/  s51's 80C517 model (Timer 0 tick, Timer 1 baud, encoder from a built-in test source)
 *   board/host/   plain C for unit tests and mcg-sim --board (driven by host_board.h)
 *
 * Interrupt routines of a board only sample inputs and set flags or counters; all work happens in
 * core_poll() on the main loop. */
#ifndef MCG_FIRMWARE_INCLUDE_HAL_H
#define MCG_FIRMWARE_INCLUDE_HAL_H

#include <stdint.h> /* uint8_t, int16_t */

/* Board id for MCG_CMD_VERSION (MCG_BOARD_*). */
uint8_t hal_board_id(void);

/* Sets up clocks, timers, UART, ports; outputs off, duty 0. Interrupts enabled on return. */
void hal_init(void);

/* Number of 1 ms ticks elapsed since the last call (0 if none), and in *pulses the encoder pulses
 * counted over those ticks (latched at the tick, not at the call). */
uint8_t hal_ticks_take(uint16_t* pulses);

/* Motor drive, duty in 1/1000 of full scale, -1000..1000 (sign = direction). */
void hal_pwm_write(int16_t duty_permille);

/* Clutch transistor and generator load relay: 1 = on. */
void hal_clutch_write(uint8_t on);
void hal_load_write(uint8_t on);

/* UART receive: 1 and the next byte in *byte, or 0 if none waiting. */
uint8_t hal_uart_rx(uint8_t* byte);
/* 1 if received bytes were lost (receive buffer full) since the last call. */
uint8_t hal_uart_rx_overrun(void);
/* Free room in the transmit buffer, in bytes. */
uint8_t hal_uart_tx_free(void);
/* Queues one byte for transmission; the caller checked hal_uart_tx_free() first. */
void hal_uart_tx(uint8_t byte);

/* The key held down now (0..15, see MCG_KEY_NONE). */
uint8_t hal_key_read(void);

/* Writes one 16-character line (row 0 or 1) of the LCD. */
void hal_lcd_write(uint8_t row, const char* text16);

#endif
