/* regs.c: the register map of mcg-protocol(7): range checks, defaults and side effects. */
#include "core.h"
#include "hal.h" /* hal_clutch_write, hal_load_write */

uint8_t g_mode;
int16_t MCG_XDATA g_rpm_cmd;
int16_t g_duty_set;
int16_t MCG_XDATA g_duty_step;
uint8_t MCG_XDATA g_service_ms;
uint8_t MCG_XDATA g_stream_on;
uint8_t MCG_XDATA g_clutch_on;
uint8_t MCG_XDATA g_load_on;

#define RPM_CMD_MIN 120 /* 420 - 300 */
#define RPM_CMD_MAX 720 /* 420 + 300 */

void regs_init(void) {
  g_mode = MCG_MODE_OPEN;
  g_rpm_cmd = 420;
  control_set_rpm_cmd(g_rpm_cmd);
  g_duty_set = 0;
  g_duty_step = 10;
  g_service_ms = 40;
  g_stream_on = 0;
  g_clutch_on = 0;
  g_load_on = 0;
  hal_clutch_write(0);
  hal_load_write(0);
}

static uint8_t flags(void) {
  MCG_SLOW uint8_t f = 0;
  if (g_saturated) {
    f |= MCG_FLAG_SATURATED;
  }
  if (g_log_running) {
    f |= MCG_FLAG_LOGGING;
  }
  if (g_log_count == MCG_LOG_POINTS) {
    f |= MCG_FLAG_LOG_FULL;
  }
  if (g_seq_state != MCG_SEQ_STOP) {
    f |= MCG_FLAG_SEQ;
  }
  return f;
}

uint8_t regs_read(uint8_t reg, int16_t* value) MCG_REENTRANT {
  int16_t v;
  switch (reg) {
    case MCG_REG_MODE:
      v = g_mode;
      break;
    case MCG_REG_RPM_CMD:
      v = g_rpm_cmd;
      break;
    case MCG_REG_DUTY:
      v = g_duty_out;
      break;
    case MCG_REG_DUTY_STEP:
      v = g_duty_step;
      break;
    case MCG_REG_DUTY_BIAS:
      v = g_duty_bias;
      break;
    case MCG_REG_KP:
      v = g_kp;
      break;
    case MCG_REG_B0:
      v = g_b0;
      break;
    case MCG_REG_B1:
      v = g_b1;
      break;
    case MCG_REG_B2:
      v = g_b2;
      break;
    case MCG_REG_COEF_FRAC:
      v = g_coef_frac;
      break;
    case MCG_REG_DUTY_MIN:
      v = g_duty_min;
      break;
    case MCG_REG_DUTY_MAX:
      v = g_duty_max;
      break;
    case MCG_REG_SERVICE_MS:
      v = g_service_ms;
      break;
    case MCG_REG_LOG_INTERVAL:
      v = g_log_interval;
      break;
    case MCG_REG_LOG_COUNT:
      v = g_log_count;
      break;
    case MCG_REG_STREAM:
      v = g_stream_on;
      break;
    case MCG_REG_CLUTCH:
      v = g_clutch_on;
      break;
    case MCG_REG_LOAD:
      v = g_load_on;
      break;
    case MCG_REG_RPM:
      v = control_rpm();
      break;
    case MCG_REG_COUNTS_16MS:
      v = (int16_t)g_counts_16ms;
      break;
    case MCG_REG_SEQ_LEN:
      v = g_seq_len;
      break;
    case MCG_REG_SEQ_STATE:
      v = g_seq_state;
      break;
    case MCG_REG_FLAGS:
      v = flags();
      break;
    case MCG_REG_RX_ERRORS:
      v = (int16_t)g_rx_errors;
      break;
    case MCG_REG_TX_DROPS:
      v = (int16_t)g_tx_drops;
      break;
    case MCG_REG_STREAM_SEQ:
      v = g_stream_seq;
      break;
    default:
      return MCG_ST_BAD_REG;
  }
  *value = v;
  return MCG_ST_OK;
}

uint8_t regs_writable(uint8_t reg) {
  switch (reg) {
    case MCG_REG_LOG_COUNT:
    case MCG_REG_RPM:
    case MCG_REG_COUNTS_16MS:
    case MCG_REG_SEQ_LEN:
    case MCG_REG_FLAGS:
    case MCG_REG_STREAM_SEQ:
      return 0;
    default:
      return reg >= MCG_REG_MODE && reg < MCG_REG_COUNT;
  }
}

static uint8_t in_range(int16_t v, int16_t lo, int16_t hi) { return v >= lo && v <= hi; }

/* Keeps the open-loop duty inside new limits. */
static void set_limits(int16_t lo, int16_t hi) {
  control_set_limits(lo, hi);
  if (g_duty_set < lo) {
    g_duty_set = lo;
  } else if (g_duty_set > hi) {
    g_duty_set = hi;
  }
}

uint8_t regs_write(uint8_t reg, int16_t v) {
  MCG_SLOW int16_t dummy;
  if (regs_read(reg, &dummy) != MCG_ST_OK) {
    return MCG_ST_BAD_REG;
  }
  if (!regs_writable(reg)) {
    return MCG_ST_READ_ONLY;
  }
  switch (reg) {
    case MCG_REG_MODE:
      if (!in_range(v, 0, MCG_MODE_COUNT - 1)) {
        return MCG_ST_RANGE;
      }
      if (v == MCG_MODE_OPEN) {
        g_duty_set = g_duty_out;
      }
      g_mode = (uint8_t)v;
      control_set_mode(g_mode);
      break;
    case MCG_REG_RPM_CMD:
      if (!in_range(v, RPM_CMD_MIN, RPM_CMD_MAX)) {
        return MCG_ST_RANGE;
      }
      g_rpm_cmd = v;
      control_set_rpm_cmd(v);
      break;
    case MCG_REG_DUTY:
      if (g_mode != MCG_MODE_OPEN) {
        return MCG_ST_BUSY;
      }
      if (!in_range(v, g_duty_min, g_duty_max)) {
        return MCG_ST_RANGE;
      }
      g_duty_set = v;
      break;
    case MCG_REG_DUTY_STEP:
      if (!in_range(v, 1, MCG_DUTY_FULL)) {
        return MCG_ST_RANGE;
      }
      g_duty_step = v;
      break;
    case MCG_REG_DUTY_BIAS:
      if (!in_range(v, -MCG_DUTY_FULL, MCG_DUTY_FULL)) {
        return MCG_ST_RANGE;
      }
      control_set_bias(v);
      break;
    case MCG_REG_KP:
      g_kp = v;
      control_refresh();
      break;
    case MCG_REG_B0:
      g_b0 = v;
      control_refresh();
      break;
    case MCG_REG_B1:
      g_b1 = v;
      control_refresh();
      break;
    case MCG_REG_B2:
      g_b2 = v;
      control_refresh();
      break;
    case MCG_REG_COEF_FRAC:
      if (!in_range(v, 0, MCG_COEF_FRAC_BITS_MAX)) {
        return MCG_ST_RANGE;
      }
      control_set_coef_frac((uint8_t)v);
      break;
    case MCG_REG_DUTY_MIN:
      if (!in_range(v, -MCG_DUTY_FULL, g_duty_max)) {
        return MCG_ST_RANGE;
      }
      set_limits(v, g_duty_max);
      break;
    case MCG_REG_DUTY_MAX:
      if (!in_range(v, g_duty_min, MCG_DUTY_FULL)) {
        return MCG_ST_RANGE;
      }
      set_limits(g_duty_min, v);
      break;
    case MCG_REG_SERVICE_MS:
      if (!in_range(v, 5, 250)) {
        return MCG_ST_RANGE;
      }
      g_service_ms = (uint8_t)v;
      break;
    case MCG_REG_LOG_INTERVAL:
      if (!in_range(v, 1, 255)) {
        return MCG_ST_RANGE;
      }
      return logger_set_interval((uint8_t)v);
    case MCG_REG_STREAM:
      if (!in_range(v, 0, 1)) {
        return MCG_ST_RANGE;
      }
      g_stream_on = (uint8_t)v;
      break;
    case MCG_REG_CLUTCH:
      if (!in_range(v, 0, 1)) {
        return MCG_ST_RANGE;
      }
      g_clutch_on = (uint8_t)v;
      hal_clutch_write(g_clutch_on);
      break;
    case MCG_REG_LOAD:
      if (!in_range(v, 0, 1)) {
        return MCG_ST_RANGE;
      }
      g_load_on = (uint8_t)v;
      hal_load_write(g_load_on);
      break;
    case MCG_REG_SEQ_STATE:
      if (!in_range(v, MCG_SEQ_STOP, MCG_SEQ_LOOP)) {
        return MCG_ST_RANGE;
      }
      return seq_set_state((uint8_t)v);
    case MCG_REG_RX_ERRORS:
      if (v != 0) {
        return MCG_ST_RANGE;
      }
      g_rx_errors = 0;
      break;
    default: /* MCG_REG_TX_DROPS, the last writable one */
      if (v != 0) {
        return MCG_ST_RANGE;
      }
      g_tx_drops = 0;
      break;
  }
  return MCG_ST_OK;
}
