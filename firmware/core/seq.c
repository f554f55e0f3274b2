/* seq.c: command sequences from the PC, stored in RAM and played back (the report's Simulink mode).
 *
 * An entry is (delay_ms u16, reg u8, value i16). Counting the first tick after the start as tick 1,
 * entry k is written, through regs_write and its checks, on tick 1 + delay_0 + ... + delay_k
 * (after that tick's control update: a new duty or command acts from the next update).
 * While the stream is on, tick 1 is the first tick that opens a stream sample (at most
 * MCG_STREAM_PERIOD_MS - 1 ticks later), so entries whose delays are multiples of MCG_STREAM_PERIOD_MS
 * fall on sample boundaries of the capture.
 * MCG_SEQ_LOOP restarts as if started on the tick of the last entry: one period lasts
 * 1 + sum(delay) ms, so a loop of zero delays still advances with time. */
#include "core.h"

static uint8_t MCG_XDATA MCG_AT(MCG_SEQ_XADDR) s_table[MCG_SEQ_MAX * MCG_SEQ_ENTRY_BYTES];
uint8_t MCG_XDATA g_seq_len;
uint8_t MCG_XDATA g_seq_state;
uint8_t MCG_XDATA g_seq_owns_set;
static MCG_XDATA uint8_t s_index;
static MCG_XDATA uint16_t s_wait_ms;
static MCG_XDATA uint8_t s_starting; /* started, waiting for a tick that opens a stream sample */

static uint16_t entry_delay(uint8_t k) {
  const uint8_t MCG_XDATA* e = s_table + (uint16_t)k * MCG_SEQ_ENTRY_BYTES;
  return (uint16_t)(e[0] | ((uint16_t)e[1] << 8));
}

/* 1 if an entry stages into, commits or discards the controller's shadow set. */
static uint8_t stages(void) {
  MCG_SLOW uint8_t k;
  for (k = 0; k < g_seq_len; ++k) {
    if (regs_staging(s_table[(uint16_t)k * MCG_SEQ_ENTRY_BYTES + 2])) {
      return 1;
    }
  }
  return 0;
}

/* The sequence stops: a set it staged and did not commit is dropped, not left for another writer. */
static void stopped(void) {
  g_seq_state = MCG_SEQ_STOP;
  if (control_owner() == MCG_WRITER_SEQ) {
    control_discard();
  }
  g_seq_owns_set = 0;
}

void seq_init(void) {
  g_seq_len = 0;
  g_seq_state = MCG_SEQ_STOP;
  g_seq_owns_set = 0;
  s_index = 0;
  s_wait_ms = 0;
  s_starting = 0;
}

uint8_t seq_write(uint8_t index, const uint8_t MCG_XDATA* entries, uint8_t n) {
  MCG_SLOW uint16_t i;
  MCG_SLOW uint8_t k;
  if (g_seq_state != MCG_SEQ_STOP) {
    return MCG_ST_BUSY;
  }
  if (index > g_seq_len || (uint16_t)index + n > MCG_SEQ_MAX) {
    return MCG_ST_RANGE;
  }
  for (k = 0; k < n; ++k) {
    MCG_SLOW uint8_t reg = entries[(uint16_t)k * MCG_SEQ_ENTRY_BYTES + 2];
    MCG_SLOW int16_t dummy;
    if (regs_read(reg, &dummy) != MCG_ST_OK) {
      return MCG_ST_BAD_REG;
    }
    if (!regs_writable(reg) || reg == MCG_REG_SEQ_STATE) {
      return MCG_ST_READ_ONLY;
    }
  }
  for (i = 0; i < (uint16_t)n * MCG_SEQ_ENTRY_BYTES; ++i) {
    s_table[(uint16_t)index * MCG_SEQ_ENTRY_BYTES + i] = entries[i];
  }
  if ((uint8_t)(index + n) > g_seq_len) {
    g_seq_len = (uint8_t)(index + n);
  }
  return MCG_ST_OK;
}

uint8_t seq_clear(void) {
  if (g_seq_state != MCG_SEQ_STOP) {
    return MCG_ST_BUSY;
  }
  g_seq_len = 0;
  return MCG_ST_OK;
}

uint8_t seq_set_state(uint8_t state) {
  if (state == MCG_SEQ_STOP) {
    stopped();
  } else {
    if (g_seq_len == 0) {
      return MCG_ST_RANGE;
    }
    if (stages()) {
      if (control_owner() != 0 && control_owner() != MCG_WRITER_SEQ) {
        return MCG_ST_BUSY;
      }
      g_seq_owns_set = 1;
    }
  }
  g_seq_state = state;
  s_index = 0;
  s_wait_ms = state != MCG_SEQ_STOP ? entry_delay(0) : 0;
  s_starting = (uint8_t)(state != MCG_SEQ_STOP);
  return MCG_ST_OK;
}

void seq_tick(void) {
  if (g_seq_state == MCG_SEQ_STOP) {
    return;
  }
  if (s_starting) {
    if (!app_stream_sample_opens()) {
      return;
    }
    s_starting = 0;
  }
  while (s_wait_ms == 0) {
    const uint8_t MCG_XDATA* e = s_table + (uint16_t)s_index * MCG_SEQ_ENTRY_BYTES;
    regs_write_by(MCG_WRITER_SEQ, e[2], (int16_t)(e[3] | ((uint16_t)e[4] << 8)));
    if (++s_index == g_seq_len) {
      s_index = 0;
      if (g_seq_state != MCG_SEQ_LOOP) {
        stopped();
        return;
      }
      s_wait_ms = entry_delay(0);
      return; /* the loop restarts as if started now */
    } else {
      s_wait_ms = entry_delay(s_index);
    }
  }
  --s_wait_ms;
}
