/* logger.c: the RAM log. 255 points at external address 0x9500, one every g_log_interval ms.
 *
 * Point k (i16, little-endian at 0x9500 + 2k) holds the encoder pulses counted during the interval
 * that ends at tick (k + 1) * interval after the start, signed with the direction of the last
 * non-zero drive (as the stream's), so rpm = point * 60000 / (2048 * interval).
 * The recording runs on the tick beside the controller and touches nothing of it: the report's
 * crash (recording set the closed-loop flag) has no way to happen here (see the regression test). */
#include "core.h"

uint16_t MCG_XDATA MCG_AT(MCG_LOG_XADDR) g_log[MCG_LOG_POINTS];
uint8_t MCG_XDATA g_log_count;
uint8_t MCG_XDATA g_log_interval;
uint8_t MCG_XDATA g_log_running;
uint8_t MCG_XDATA g_dump_next;
static MCG_XDATA uint8_t s_elapsed_ms;
static MCG_XDATA int16_t s_pulses;

void logger_init(void) {
  g_log_count = 0;
  g_log_interval = 1; /* the register's power-on value comes with regs_init */
  g_log_running = 0;
  s_elapsed_ms = 0;
  s_pulses = 0;
  g_dump_next = MCG_LOG_DUMP_FRAMES;
}

uint8_t logger_start(void) {
  if (g_dump_next < MCG_LOG_DUMP_FRAMES) {
    return MCG_ST_BUSY;
  }
  g_log_count = 0;
  s_elapsed_ms = 0;
  s_pulses = 0;
  g_log_running = 1;
  return MCG_ST_OK;
}

uint8_t logger_dump_start(void) {
  if (g_log_running) {
    return MCG_ST_BUSY;
  }
  g_dump_next = 0;
  return MCG_ST_OK;
}

uint8_t logger_set_interval(uint8_t interval_ms) {
  if (g_log_running) {
    return MCG_ST_BUSY;
  }
  g_log_interval = interval_ms;
  return MCG_ST_OK;
}

void logger_tick(uint8_t pulses) {
  if (!g_log_running) {
    return;
  }
  s_pulses = (int16_t)(g_count_neg ? s_pulses - pulses : s_pulses + pulses);
  if (++s_elapsed_ms < g_log_interval) {
    return;
  }
  g_log[g_log_count] = (uint16_t)s_pulses;
  s_pulses = 0;
  s_elapsed_ms = 0;
  if (++g_log_count == MCG_LOG_POINTS) {
    g_log_running = 0;
  }
}
