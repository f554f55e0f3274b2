/* frame.c: framing with CRC-16 and a parser that resynchronises after garbage or truncation. */
#include "core.h"
#include "hal.h" /* hal_uart_tx, hal_uart_tx_free */

#define FRAME_BUF_SIZE (MCG_MAX_PAYLOAD + MCG_FRAME_OVERHEAD)

/* Bytes of the frame being received; s_buf[0] is always MCG_SYNC when s_fill > 0. */
static uint8_t MCG_XDATA s_buf[FRAME_BUF_SIZE];
static MCG_XDATA uint8_t s_fill;
static MCG_XDATA uint8_t s_idle_ms; /* ticks since the last byte of a partial frame */
static uint8_t MCG_XDATA s_err_payload[1];
uint16_t MCG_XDATA g_rx_errors;
uint16_t MCG_XDATA g_tx_drops;

void frame_init(void) {
  s_fill = 0;
  s_idle_ms = 0;
  g_rx_errors = 0;
  g_tx_drops = 0;
}

static void report_error(uint8_t status) {
  ++g_rx_errors;
  s_err_payload[0] = status;
  frame_send(MCG_MSG_ERROR, s_err_payload, 1);
}

/* Drops the first n bytes and then everything up to the next SYNC, keeping the rest: the bytes
 * already received are scanned again, so a real frame that began inside a damaged one is not lost. */
static void drop(uint8_t n) {
  MCG_SLOW uint8_t i;
  while (n < s_fill && s_buf[n] != MCG_SYNC) {
    ++n;
  }
  for (i = 0; n < s_fill; ++i, ++n) {
    s_buf[i] = s_buf[n];
  }
  s_fill = i;
}

/* Checks the buffer for a complete good frame, a framing error, or the need for more bytes. */
static void scan(void) {
  while (s_fill > 0) {
    MCG_SLOW uint8_t len;
    MCG_SLOW uint8_t total;
    MCG_SLOW uint16_t crc;
    MCG_SLOW uint8_t i;
    if (s_fill < 2) {
      return;
    }
    len = s_buf[1];
    if (len > MCG_MAX_PAYLOAD) {
      report_error(MCG_ST_TOO_LONG);
      drop(1);
      continue;
    }
    total = (uint8_t)(len + MCG_FRAME_OVERHEAD);
    if (s_fill < total) {
      return;
    }
    crc = MCG_CRC_INIT;
    for (i = 1; i < (uint8_t)(total - 2); ++i) {
      crc = (uint16_t)mcg_crc16_update(crc, s_buf[i]);
    }
    if (s_buf[total - 2] != (uint8_t)(crc & 0xFFu) || s_buf[total - 1] != (uint8_t)(crc >> 8)) {
      report_error(MCG_ST_BAD_CRC);
      drop(1);
      continue;
    }
    app_dispatch(s_buf[2], s_buf + 3, len);
    drop(total);
  }
}

void frame_rx_byte(uint8_t byte) {
  s_idle_ms = 0;
  if (s_fill == 0 && byte != MCG_SYNC) {
    return; /* line noise between frames */
  }
  s_buf[s_fill++] = byte;
  scan();
}

void frame_rx_tick(void) {
  if (s_fill == 0) {
    return;
  }
  if (++s_idle_ms > MCG_FRAME_TIMEOUT_MS) {
    /* Every byte held arrived before the silence: a candidate the rescan finds that still needs
     * more bytes is as stale as the one dropped, so all of them go now (one timeout per SYNC in
     * the junk kept the link deaf for 21 ms times their number). */
    s_idle_ms = 0;
    report_error(MCG_ST_TIMEOUT);
    do {
      drop(1);
      scan();
    } while (s_fill > 0);
  }
}

void frame_rx_overrun(void) {
  s_fill = 0;
  report_error(MCG_ST_OVERRUN);
}

uint8_t frame_send(uint8_t cmd, const uint8_t MCG_XDATA* payload, uint8_t len) MCG_REENTRANT {
  uint16_t crc = MCG_CRC_INIT;
  uint8_t i;
  if (hal_uart_tx_free() < (uint8_t)(len + MCG_FRAME_OVERHEAD)) {
    ++g_tx_drops;
    return 0;
  }
  hal_uart_tx(MCG_SYNC);
  hal_uart_tx(len);
  crc = (uint16_t)mcg_crc16_update(crc, len);
  hal_uart_tx(cmd);
  crc = (uint16_t)mcg_crc16_update(crc, cmd);
  for (i = 0; i < len; ++i) {
    hal_uart_tx(payload[i]);
    crc = (uint16_t)mcg_crc16_update(crc, payload[i]);
  }
  hal_uart_tx((uint8_t)(crc & 0xFFu));
  hal_uart_tx((uint8_t)(crc >> 8));
  return 1;
}

static uint8_t MCG_XDATA s_reply[MCG_MAX_PAYLOAD];

uint8_t frame_reply(uint8_t cmd, uint8_t status, const uint8_t MCG_XDATA* data, uint8_t len) MCG_REENTRANT {
  uint8_t i;
  s_reply[0] = status;
  for (i = 0; i < len; ++i) {
    s_reply[i + 1] = data[i];
  }
  return frame_send((uint8_t)(cmd | MCG_REPLY_BIT), s_reply, (uint8_t)(len + 1));
}
