/* host_board.h: drive the firmware core from a host program, one 1 ms tick at a time.
 *
 * The host board layer implements hal.h with plain memory, so the same core that runs on the 8051
 * runs inside unit tests and inside mcg-sim --board against the plant model. The core keeps its
 * state in globals, as on the 8051: there is one board per process, and calls must come from one
 * thread.
 *
 * A caller's loop, per simulated millisecond:
 *
 *   host_board_rx(bytes_from_pc, n);            // what arrived on the serial line
 *   host_board_tick(encoder_pulses_this_ms);    // pulses counted by the encoder input this 1 ms
 *   duty = host_board_duty();                   // -1000..1000, 1/1000 of full scale, sign = direction
 *   clutch = host_board_clutch(); load = host_board_load();
 *   n = host_board_tx(buf, sizeof buf);         // what the board sent on the serial line
 *
 * The serial line runs at host_board_set_baud() (10 bit times per byte, 8N1), so the stream and the
 * log dump meet the same byte budget as on the board; 0 (the default after reset) moves bytes
 * without limit. */
#ifndef MCG_FIRMWARE_BOARD_HOST_HOST_BOARD_H
#define MCG_FIRMWARE_BOARD_HOST_HOST_BOARD_H

#include <stddef.h> /* size_t */
#include <stdint.h> /* uint8_t, int16_t, uint16_t, uint32_t */

#ifdef __cplusplus
extern "C" {
#endif

/* Power-on reset: line buffers emptied, line unlimited, no key, then the core's power-on state. */
void host_board_reset(void);

/* Serial line rate in baud (e.g. 9600); 0 = unlimited. */
void host_board_set_baud(uint32_t baud);

/* Advances the board by one 1 ms tick in which the encoder input counted encoder_pulses pulses
 * (pulses are counted without direction, as by the 80C515's counter input), then runs the main
 * loop: serial bytes move at the line rate, the core runs its control update and services. */
void host_board_tick(uint16_t encoder_pulses);

/* Advances by one tick without running the main loop, as when the board's main loop is held up
 * (an LCD refresh): the next host_board_tick runs every pending tick, sharing the pulses counted
 * meanwhile evenly among them, as the board does. */
void host_board_stall(uint16_t encoder_pulses);

/* Bytes arriving from the PC; they reach the UART at the line rate during the next ticks.
 * Returns how many were accepted (the line buffer holds HOST_BOARD_LINE_BYTES). */
size_t host_board_rx(const uint8_t* data, size_t n);
#define HOST_BOARD_LINE_BYTES 4096u

/* Copies up to cap bytes the board has transmitted since the last call; returns the count. */
size_t host_board_tx(uint8_t* out, size_t cap);

/* Makes the UART report an overrun (a received byte lost), as a stalled board would. */
void host_board_uart_overrun(void);

/* Outputs: PWM duty (1/1000, -1000..1000), clutch transistor and load relay (1 = on). */
int16_t host_board_duty(void);
uint8_t host_board_clutch(void);
uint8_t host_board_load(void);

/* The key held down (0..15) or MCG_KEY_NONE; sampled by the core every service period. */
void host_board_key(uint8_t key);

/* The LCD's rows 0 and 1 as last written: 16 characters, NUL-terminated. */
const char* host_board_lcd(uint8_t row);

/* The RAM log (MCG_LOG_POINTS points, as at external address MCG_LOG_XADDR on the board). */
const uint16_t* host_board_log(void);

/* Milliseconds (ticks) since reset. */
uint32_t host_board_time_ms(void);

/* The register table as the protocol's READ and WRITE commands reach it, without the serial line:
 * for a host that runs the core as a controller only (mcg-sim's closed loop). Return MCG_ST_OK or
 * the status the command would answer. */
uint8_t host_board_reg_write(uint8_t reg, int16_t value);
uint8_t host_board_reg_read(uint8_t reg, int16_t* value);
/* A write as one atomic change (regs_apply): a register of the controller's set is staged onto the
 * active set and committed, as mcg-serial set does it. */
uint8_t host_board_reg_apply(uint8_t reg, int16_t value);

#ifdef __cplusplus
}
#endif

#endif
