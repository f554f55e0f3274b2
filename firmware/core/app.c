/* app.c: the service loop, command dispatch, stream blocks and sending the RAM log dump. */
#include "core.h"
#include "hal.h" /* hal_ticks_take, hal_uart_rx, hal_uart_tx_free, hal_board_id */

uint8_t MCG_XDATA g_stream_seq;
uint8_t MCG_XDATA g_count_neg;

static MCG_XDATA uint8_t s_service_ms;   /* ticks since the last keypad service */
static MCG_XDATA uint16_t s_lcd_ms;      /* ticks since the last LCD refresh */
static MCG_XDATA uint8_t s_stream_phase; /* ticks recorded into the present sample */
static MCG_XDATA uint8_t s_stream_count; /* samples in the present block */
static MCG_XDATA int16_t s_stream_pulses; /* signed pulses of the present sample */
static MCG_XDATA int16_t s_stream_duty;   /* sum of the duty over the present sample's ticks */
static MCG_XDATA uint8_t s_stream_flags;  /* MCG_STREAM_BIT_CMD if rpm_cmd changed in the sample */
static MCG_XDATA int16_t s_stream_cmd;    /* rpm_cmd seen by the last tick */
static uint8_t MCG_XDATA s_block[MCG_STREAM_PAYLOAD];
static uint8_t MCG_XDATA s_data[MCG_LOGDATA_HEADER + 2u * MCG_LOG_DUMP_CHUNK];

static void put16(uint8_t MCG_XDATA* p, int16_t v) {
  p[0] = (uint8_t)((uint16_t)v & 0xFFu);
  p[1] = (uint8_t)((uint16_t)v >> 8);
}

void core_init(void) {
  frame_init();
  control_init();
  logger_init();
  seq_init();
  excite_init();
  regs_init(); /* last: the register defaults go through regs_write into the modules above */
  menu_init();
  g_stream_seq = 0;
  s_service_ms = 0;
  s_lcd_ms = 0;
  s_stream_phase = 0;
  s_stream_count = 0;
  s_stream_pulses = 0;
  s_stream_duty = 0;
  s_stream_flags = 0;
  s_stream_cmd = g_rpm_cmd;
  g_count_neg = 0;
  hal_pwm_write(0);
  menu_refresh();
}

/* Records the tick that just ended: the outputs still set are those that acted during it, and
 * `pulses` were counted during it. One sample every MCG_STREAM_PERIOD_MS ticks, one block every
 * MCG_STREAM_SAMPLES samples. A block that finds no transmit room is dropped, and its sequence number
 * with it, so the host counts the loss. */
static void stream_tick(uint8_t pulses) {
  uint8_t MCG_XDATA* MCG_SLOW p;
  MCG_SLOW int16_t v;
  if (g_duty_out > 0) {
    g_count_neg = 0;
  } else if (g_duty_out < 0) {
    g_count_neg = 1;
  }
  if (g_rpm_cmd != s_stream_cmd) {
    s_stream_cmd = g_rpm_cmd;
    s_stream_flags = MCG_STREAM_BIT_CMD;
  }
  if (!g_stream_on) {
    s_stream_phase = 0;
    s_stream_count = 0;
    s_stream_pulses = 0;
    s_stream_duty = 0;
    s_stream_flags = 0;
    return;
  }
  s_stream_pulses = (int16_t)(g_count_neg ? s_stream_pulses - pulses : s_stream_pulses + pulses);
  s_stream_duty = (int16_t)(s_stream_duty + g_duty_out);
  if (++s_stream_phase < MCG_STREAM_PERIOD_MS) {
    return;
  }
  s_stream_phase = 0;
  p = s_block + MCG_STREAM_HEADER + MCG_STREAM_SAMPLE_BYTES * s_stream_count;
  v = s_stream_duty;
  v = (int16_t)(v >= 0 ? (v + (int16_t)(MCG_STREAM_PERIOD_MS / 2u)) / (int16_t)MCG_STREAM_PERIOD_MS
                       : -((-v + (int16_t)(MCG_STREAM_PERIOD_MS / 2u)) / (int16_t)MCG_STREAM_PERIOD_MS));
  p[0] = (uint8_t)((uint16_t)v & 0xFFu);
  p[1] = (uint8_t)(((uint16_t)v >> 8) & 0x07u);
  v = s_stream_pulses;
  if (v > MCG_STREAM_COUNTS_MAX) {
    v = MCG_STREAM_COUNTS_MAX;
  } else if (v < -MCG_STREAM_COUNTS_MAX) {
    v = -MCG_STREAM_COUNTS_MAX;
  }
  p[1] = (uint8_t)(p[1] | (uint8_t)(((uint16_t)v & 0x1Fu) << 3));
  p[2] = (uint8_t)((((uint16_t)v >> 5) & 0x1Fu) | s_stream_flags);
  if (g_clutch_on) {
    p[2] |= MCG_STREAM_BIT_CLUTCH;
  }
  if (g_load_on) {
    p[2] |= MCG_STREAM_BIT_LOAD;
  }
  s_stream_pulses = 0;
  s_stream_duty = 0;
  s_stream_flags = 0;
  if (++s_stream_count < MCG_STREAM_SAMPLES) {
    return;
  }
  s_stream_count = 0;
  s_block[0] = g_stream_seq++;
  put16(s_block + 1, g_rpm_cmd);
  frame_send(MCG_MSG_STREAM, s_block, (uint8_t)sizeof s_block);
}

uint8_t app_stream_sample_opens(void) { return (uint8_t)(!g_stream_on || s_stream_phase == 0); }

static void tick(uint8_t pulses) {
  stream_tick(pulses);
  excite_tick();
  control_tick(pulses);
  speed_tick(pulses);
  logger_tick(pulses);
  seq_tick();
  frame_rx_tick();
  if (++s_service_ms >= g_service_ms) {
    s_service_ms = 0;
    menu_service();
  }
  if (++s_lcd_ms >= MENU_LCD_REFRESH_MS) {
    s_lcd_ms = 0;
    menu_refresh();
  }
}

/* Sends the next chunks of the log while the transmit buffer has room for a whole one. */
static void dump_pump(void) {
  /* While streaming, leave room for a stream block and a short answer: the dump takes only the
   * spare bytes of the line, and no block is dropped for it. */
  MCG_SLOW uint8_t need = (uint8_t)(MCG_FRAME_OVERHEAD + sizeof s_data);
  if (g_stream_on) {
    need = (uint8_t)(need + MCG_FRAME_OVERHEAD + sizeof s_block + MCG_FRAME_OVERHEAD + 1u + sizeof(McgRegisterAnswer));
  }
  while (g_dump_next < MCG_LOG_DUMP_FRAMES && hal_uart_tx_free() >= need) {
    MCG_SLOW uint8_t first = (uint8_t)(g_dump_next * MCG_LOG_DUMP_CHUNK);
    MCG_SLOW uint8_t n = (uint8_t)(MCG_LOG_POINTS - first);
    MCG_SLOW uint8_t i;
    if (n > MCG_LOG_DUMP_CHUNK) {
      n = MCG_LOG_DUMP_CHUNK;
    }
    s_data[0] = first;
    s_data[1] = n;
    for (i = 0; i < n; ++i) {
      put16(s_data + MCG_LOGDATA_HEADER + 2u * i, (int16_t)g_log[first + i]);
    }
    frame_send(MCG_MSG_LOG_DATA, s_data, (uint8_t)(MCG_LOGDATA_HEADER + 2u * n));
    ++g_dump_next;
  }
}

void core_poll(void) {
  MCG_SLOW uint16_t pulses;
  MCG_SLOW uint8_t n = hal_ticks_take(&pulses);
  MCG_SLOW uint8_t byte;
  /* Late by several ticks (only if something overran a tick): share the pulses out evenly. */
  while (n > 0) {
    MCG_SLOW uint16_t share = (uint16_t)(n == 1 ? pulses : pulses / n);
    pulses = (uint16_t)(pulses - share);
    tick(share > 255u ? 255u : (uint8_t)share);
    --n;
  }
  if (hal_uart_rx_overrun()) {
    frame_rx_overrun();
  }
  while (hal_uart_rx(&byte)) {
    frame_rx_byte(byte);
  }
  dump_pump();
}

/* Room for the largest answer: a MCG_CMD_READ_MANY of MCG_READ_MANY_MAX registers. */
static uint8_t MCG_XDATA s_ans[sizeof(McgReadManyRequest) + 2u * MCG_READ_MANY_MAX];

void app_dispatch(uint8_t cmd, const uint8_t MCG_XDATA* payload, uint8_t len) {
  MCG_SLOW uint8_t st;
  MCG_SLOW int16_t value = 0;
  MCG_SLOW uint8_t k;
  switch (cmd) {
    case MCG_CMD_VERSION:
      if (len != 0) {
        break;
      }
      s_ans[0] = MCG_PROTOCOL_VERSION;
      s_ans[1] = MCG_FW_VERSION_MAJOR;
      s_ans[2] = MCG_FW_VERSION_MINOR;
      s_ans[3] = MCG_FW_VERSION_PATCH;
      s_ans[4] = hal_board_id();
      frame_reply(cmd, MCG_ST_OK, s_ans, (uint8_t)sizeof(McgVersionAnswer));
      return;
    case MCG_CMD_READ:
    case MCG_CMD_WRITE:
      if (len != (cmd == MCG_CMD_READ ? sizeof(McgReadRequest) : sizeof(McgWriteRequest))) {
        break;
      }
      /* A write answers what the register now holds: a staged one, its shadow value. */
      if (cmd == MCG_CMD_WRITE) {
        st = regs_write(payload[0], (int16_t)(payload[1] | ((uint16_t)payload[2] << 8)));
        if (st == MCG_ST_OK) {
          st = regs_read_staged(payload[0], &value);
        }
      } else {
        st = regs_read(payload[0], &value);
      }
      if (st != MCG_ST_OK) {
        frame_reply(cmd, st, s_ans, 0);
        return;
      }
      s_ans[0] = payload[0];
      put16(s_ans + 1, value);
      frame_reply(cmd, MCG_ST_OK, s_ans, (uint8_t)sizeof(McgRegisterAnswer));
      return;
    case MCG_CMD_READ_MANY:
      if (len != sizeof(McgReadManyRequest) || payload[1] == 0 || payload[1] > MCG_READ_MANY_MAX) {
        break;
      }
      s_ans[0] = payload[0];
      s_ans[1] = payload[1];
      for (k = 0; k < payload[1]; ++k) {
        if (regs_read((uint8_t)(payload[0] + k), &value) != MCG_ST_OK) {
          frame_reply(cmd, MCG_ST_BAD_REG, s_ans, 0);
          return;
        }
        put16(s_ans + sizeof(McgReadManyRequest) + 2u * k, value);
      }
      frame_reply(cmd, MCG_ST_OK, s_ans, (uint8_t)(sizeof(McgReadManyRequest) + 2u * payload[1]));
      return;
    case MCG_CMD_READ_LIST:
      if (len == 0 || len > MCG_READ_MANY_MAX) {
        break;
      }
      s_ans[0] = payload[0];
      s_ans[1] = len;
      for (k = 0; k < len; ++k) {
        if (regs_read(payload[k], &value) != MCG_ST_OK) {
          frame_reply(cmd, MCG_ST_BAD_REG, s_ans, 0);
          return;
        }
        put16(s_ans + sizeof(McgReadManyRequest) + 2u * k, value);
      }
      frame_reply(cmd, MCG_ST_OK, s_ans, (uint8_t)(sizeof(McgReadManyRequest) + 2u * len));
      return;
    case MCG_CMD_LOG_START:
      if (len != 0) {
        break;
      }
      frame_reply(cmd, logger_start(), s_ans, 0);
      return;
    case MCG_CMD_LOG_DUMP:
      if (len != 0) {
        break;
      }
      st = logger_dump_start();
      s_ans[0] = g_log_count;
      s_ans[1] = g_log_interval;
      frame_reply(cmd, st, s_ans, st == MCG_ST_OK ? (uint8_t)sizeof(McgDumpAnswer) : 0u);
      return;
    case MCG_CMD_SEQ_WRITE:
      if (len < 1u + MCG_SEQ_ENTRY_BYTES || (len - 1u) % MCG_SEQ_ENTRY_BYTES != 0 ||
          (len - 1u) / MCG_SEQ_ENTRY_BYTES > MCG_SEQ_WRITE_MAX) {
        break;
      }
      value = (int16_t)((len - 1u) / MCG_SEQ_ENTRY_BYTES);
      st = seq_write(payload[0], payload + 1, (uint8_t)value);
      s_ans[0] = (uint8_t)(payload[0] + value);
      frame_reply(cmd, st, s_ans, st == MCG_ST_OK ? (uint8_t)sizeof(McgSeqWriteAnswer) : 0u);
      return;
    case MCG_CMD_SEQ_CLEAR:
      if (len != 0) {
        break;
      }
      frame_reply(cmd, seq_clear(), s_ans, 0);
      return;
    default:
      frame_reply(cmd, MCG_ST_BAD_CMD, s_ans, 0);
      return;
  }
  frame_reply(cmd, MCG_ST_BAD_LENGTH, s_ans, 0);
}
