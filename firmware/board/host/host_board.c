/* host_board.c: hal.h in plain memory, and the host_board.h driver around the core. */
#include "host_board.h"

#include "../../core/core.h" /* core_init, core_poll, g_log */
#include "hal.h"             /* the seam implemented here */

#define RX_RING 64u  /* the 8051 layers' receive ring */
#define TX_RING 128u /* the 8051 layers' transmit ring */

/* A byte queue: the UART rings and the two line buffers. */
typedef struct {
  uint8_t* buf;
  size_t cap, head, count;
} Queue;

static uint8_t s_rx_mem[RX_RING], s_tx_mem[TX_RING];
static uint8_t s_in_mem[HOST_BOARD_LINE_BYTES], s_out_mem[HOST_BOARD_LINE_BYTES];
static Queue s_rx = {s_rx_mem, RX_RING, 0, 0};
static Queue s_tx = {s_tx_mem, TX_RING, 0, 0};
static Queue s_line_in = {s_in_mem, HOST_BOARD_LINE_BYTES, 0, 0};
static Queue s_line_out = {s_out_mem, HOST_BOARD_LINE_BYTES, 0, 0};

static uint32_t s_baud;
static uint32_t s_in_credit, s_out_credit; /* bit times available, x 1000 per tick */
static uint8_t s_ticks;
static uint16_t s_pulses;
static uint8_t s_overrun;
static int16_t s_duty;
static uint8_t s_clutch, s_load;
static uint8_t s_key;
static char s_lcd[2][17];
static uint32_t s_time_ms;

static void q_clear(Queue* q) {
  q->head = 0;
  q->count = 0;
}

static void q_push(Queue* q, uint8_t b) {
  q->buf[(q->head + q->count) % q->cap] = b;
  ++q->count;
}

static uint8_t q_pop(Queue* q) {
  uint8_t b = q->buf[q->head];
  q->head = (q->head + 1) % q->cap;
  --q->count;
  return b;
}

/* hal.h ------------------------------------------------------------------------------------------ */
uint8_t hal_board_id(void) { return MCG_BOARD_HOST; }

void hal_init(void) {}

uint8_t hal_ticks_take(uint16_t* pulses) {
  uint8_t n = s_ticks;
  *pulses = s_pulses;
  s_ticks = 0;
  s_pulses = 0;
  return n;
}

void hal_pwm_write(int16_t duty_permille) { s_duty = duty_permille; }

void hal_clutch_write(uint8_t on) { s_clutch = on; }

void hal_load_write(uint8_t on) { s_load = on; }

uint8_t hal_uart_rx(uint8_t* byte) {
  if (s_rx.count == 0) {
    return 0;
  }
  *byte = q_pop(&s_rx);
  return 1;
}

uint8_t hal_uart_rx_overrun(void) {
  uint8_t o = s_overrun;
  s_overrun = 0;
  return o;
}

uint8_t hal_uart_tx_free(void) { return (uint8_t)(s_tx.cap - s_tx.count); }

void hal_uart_tx(uint8_t byte) { q_push(&s_tx, byte); }

uint8_t hal_key_read(void) { return s_key; }

void hal_lcd_write(uint8_t row, const char* text16) {
  uint8_t i;
  for (i = 0; i < 16 && text16[i]; ++i) {
    s_lcd[row][i] = text16[i];
  }
  s_lcd[row][i] = 0;
}

/* host_board.h ----------------------------------------------------------------------------------- */
void host_board_reset(void) {
  q_clear(&s_rx);
  q_clear(&s_tx);
  q_clear(&s_line_in);
  q_clear(&s_line_out);
  s_baud = 0;
  s_in_credit = 0;
  s_out_credit = 0;
  s_ticks = 0;
  s_pulses = 0;
  s_overrun = 0;
  s_duty = 0;
  s_clutch = 0;
  s_load = 0;
  s_key = MCG_KEY_NONE;
  s_lcd[0][0] = 0;
  s_lcd[1][0] = 0;
  s_time_ms = 0;
  hal_init();
  core_init();
}

void host_board_set_baud(uint32_t baud) {
  s_baud = baud;
  s_in_credit = 0;
  s_out_credit = 0;
}

/* Whether one more byte fits in the line's budget this tick (10 bit times per byte). */
static int line_allows(uint32_t* credit) {
  if (s_baud == 0) {
    return 1;
  }
  if (*credit < 10u * 1000u) {
    return 0;
  }
  *credit -= 10u * 1000u;
  return 1;
}

/* Moves transmitted bytes from the UART ring onto the line, within the line's budget. */
static void drain_tx(void) {
  while (s_tx.count > 0 && s_line_out.count < s_line_out.cap && line_allows(&s_out_credit)) {
    q_push(&s_line_out, q_pop(&s_tx));
  }
}

void host_board_stall(uint16_t encoder_pulses) {
  ++s_time_ms;
  if (s_ticks < 255u) {
    ++s_ticks;
  }
  s_pulses = (uint16_t)(s_pulses + encoder_pulses);
}

void host_board_tick(uint16_t encoder_pulses) {
  host_board_stall(encoder_pulses);
  if (s_baud != 0) {
    /* carry at most one tick of unused line time, as the line cannot store it */
    s_in_credit = (s_in_credit % 10000u) + s_baud;
    s_out_credit = (s_out_credit % 10000u) + s_baud;
  }
  core_poll();
  drain_tx();
  /* Received bytes enter the UART ring; the core's main loop runs between batches, as the real
   * main loop runs far more often than bytes arrive, and the line takes answers meanwhile. */
  while (s_line_in.count > 0 && line_allows(&s_in_credit)) {
    q_push(&s_rx, q_pop(&s_line_in));
    if (s_rx.count == s_rx.cap || s_line_in.count == 0) {
      core_poll();
      drain_tx();
    }
  }
  core_poll();
  drain_tx();
}

size_t host_board_rx(const uint8_t* data, size_t n) {
  size_t i;
  for (i = 0; i < n && s_line_in.count < s_line_in.cap; ++i) {
    q_push(&s_line_in, data[i]);
  }
  return i;
}

size_t host_board_tx(uint8_t* out, size_t cap) {
  size_t i;
  for (i = 0; i < cap && s_line_out.count > 0; ++i) {
    out[i] = q_pop(&s_line_out);
  }
  return i;
}

void host_board_uart_overrun(void) { s_overrun = 1; }

int16_t host_board_duty(void) { return s_duty; }

uint8_t host_board_clutch(void) { return s_clutch; }

uint8_t host_board_load(void) { return s_load; }

void host_board_key(uint8_t key) { s_key = key; }

const char* host_board_lcd(uint8_t row) { return s_lcd[row & 1u]; }

const uint16_t* host_board_log(void) { return g_log; }

uint32_t host_board_time_ms(void) { return s_time_ms; }

uint8_t host_board_reg_write(uint8_t reg, int16_t value) { return regs_write(reg, value); }

uint8_t host_board_reg_apply(uint8_t reg, int16_t value) { return regs_apply(reg, value); }

uint8_t host_board_reg_read(uint8_t reg, int16_t* value) { return regs_read(reg, value); }
