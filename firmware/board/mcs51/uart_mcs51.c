/* uart_mcs51.c: interrupt-driven receive and transmit rings for the 8051 UART. */
#include "uart_mcs51.h"

#include <8051.h>   /* SCON, SBUF, RI, TI, ES */
#include <stdint.h> /* uint8_t */

#include "hal.h" /* hal_uart_* */

static volatile uint8_t MCG_XDATA s_rx_buf[UART_RX_RING];
static volatile uint8_t MCG_XDATA s_tx_buf[UART_TX_RING];
static volatile uint8_t s_rx_head, s_rx_tail, s_rx_overrun;
static volatile uint8_t s_tx_head, s_tx_tail, s_tx_busy;

void uart_init(void) {
  s_rx_head = 0;
  s_rx_tail = 0;
  s_rx_overrun = 0;
  s_tx_head = 0;
  s_tx_tail = 0;
  s_tx_busy = 0;
  SCON = 0x50; /* mode 1: 8 data bits, 1 stop bit, receiver on */
  ES = 1;
}

void uart_isr(void) MCG_ISR(4) {
  if (RI) {
    uint8_t next = (uint8_t)((s_rx_head + 1u) & (UART_RX_RING - 1u));
    RI = 0;
    if (next == s_rx_tail) {
      s_rx_overrun = 1;
    } else {
      s_rx_buf[s_rx_head] = SBUF;
      s_rx_head = next;
    }
  }
  if (TI) {
    TI = 0; /* must be cleared, or the ISR runs forever */
    if (s_tx_tail != s_tx_head) {
      SBUF = s_tx_buf[s_tx_tail];
      s_tx_tail = (uint8_t)((s_tx_tail + 1u) & (UART_TX_RING - 1u));
    } else {
      s_tx_busy = 0;
    }
  }
}

uint8_t hal_uart_rx(uint8_t* byte) {
  if (s_rx_tail == s_rx_head) {
    return 0;
  }
  *byte = s_rx_buf[s_rx_tail];
  s_rx_tail = (uint8_t)((s_rx_tail + 1u) & (UART_RX_RING - 1u));
  return 1;
}

uint8_t hal_uart_rx_overrun(void) {
  uint8_t o;
  ES = 0;
  o = s_rx_overrun;
  s_rx_overrun = 0;
  ES = 1;
  return o;
}

uint8_t hal_uart_tx_free(void) {
  return (uint8_t)(UART_TX_RING - 1u - ((uint8_t)(s_tx_head - s_tx_tail) & (UART_TX_RING - 1u)));
}

void hal_uart_tx(uint8_t byte) {
  s_tx_buf[s_tx_head] = byte;
  s_tx_head = (uint8_t)((s_tx_head + 1u) & (UART_TX_RING - 1u));
  ES = 0;
  if (!s_tx_busy) {
    s_tx_busy = 1;
    TI = 1; /* the interrupt sends the first byte */
  }
  ES = 1;
}
