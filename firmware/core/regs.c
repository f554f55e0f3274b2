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

/* The columns of MCG_REGISTERS the firmware needs, indexed by id - 1, in code memory. */
#define REG_ACCESS(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) access,
#define REG_MIN(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) lo,
#define REG_MAX(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) hi,
#define REG_DEFAULT(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) def,
static MCG_CODE uint8_t k_access[] = {MCG_REGISTERS(REG_ACCESS)};
static MCG_CODE int16_t k_min[] = {MCG_REGISTERS(REG_MIN)};
static MCG_CODE int16_t k_max[] = {MCG_REGISTERS(REG_MAX)};
static MCG_CODE int16_t k_default[] = {MCG_REGISTERS(REG_DEFAULT)};
/* One row per id 0x01..MCG_REG_COUNT-1 (the host checks the order): a compile error otherwise. */
typedef char regs_one_row_per_id[sizeof k_access == MCG_REG_COUNT - 1u ? 1 : -1];

/* Power-on values: each writable register gets its table default through regs_write, in id order,
 * with the write's side effects (outputs); the controller's set (open loop) is then committed. */
void regs_init(void) {
  MCG_SLOW uint8_t reg;
  g_mode = MCG_MODE_OPEN;
  g_duty_set = 0;
  for (reg = MCG_REG_MODE; reg < MCG_REG_COUNT; ++reg) {
    if (k_access[reg - 1u] != MCG_RO && reg != MCG_REG_COMMIT) {
      regs_write(reg, k_default[reg - 1u]);
    }
  }
  control_commit();
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
  if (g_seq_owns_set) {
    f |= MCG_FLAG_SEQ_SET;
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
      v = g_clutch_on ? MCG_CLUTCH_ENGAGED : MCG_CLUTCH_ATTACHED;
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
    case MCG_REG_COMMIT:
      v = control_pending();
      break;
    case MCG_REG_EXC_KIND:
      v = g_exc_kind;
      break;
    case MCG_REG_EXC_ORDER:
      v = g_exc_order;
      break;
    case MCG_REG_EXC_STEPS:
      v = g_exc_steps;
      break;
    case MCG_REG_EXC_DIV:
      v = (int16_t)g_exc_div;
      break;
    case MCG_REG_EXC_AMP:
      v = g_exc_amp;
      break;
    case MCG_REG_EXC_OFFSET:
      v = g_exc_offset;
      break;
    case MCG_REG_EXC_PERIODS:
      v = g_exc_periods;
      break;
    case MCG_REG_EXC_RUN:
      v = g_exc_run;
      break;
    case MCG_REG_EXC_F0:
      v = (int16_t)g_exc_f0;
      break;
    case MCG_REG_EXC_F1:
      v = (int16_t)g_exc_f1;
      break;
    case MCG_REG_EXC_SWEEP:
      v = (int16_t)g_exc_sweep;
      break;
    default:
      return MCG_ST_BAD_REG;
  }
  *value = v;
  return MCG_ST_OK;
}

uint8_t regs_read_staged(uint8_t reg, int16_t* value) {
  switch (reg) {
    case MCG_REG_MODE:
      *value = g_ctl_shadow.mode;
      return MCG_ST_OK;
    case MCG_REG_DUTY_BIAS:
      *value = g_ctl_shadow.duty_bias;
      return MCG_ST_OK;
    case MCG_REG_KP:
      *value = g_ctl_shadow.kp;
      return MCG_ST_OK;
    case MCG_REG_B0:
      *value = g_ctl_shadow.b0;
      return MCG_ST_OK;
    case MCG_REG_B1:
      *value = g_ctl_shadow.b1;
      return MCG_ST_OK;
    case MCG_REG_B2:
      *value = g_ctl_shadow.b2;
      return MCG_ST_OK;
    case MCG_REG_COEF_FRAC:
      *value = g_ctl_shadow.coef_frac;
      return MCG_ST_OK;
    case MCG_REG_DUTY_MIN:
      *value = g_ctl_shadow.duty_min;
      return MCG_ST_OK;
    case MCG_REG_DUTY_MAX:
      *value = g_ctl_shadow.duty_max;
      return MCG_ST_OK;
    default:
      return regs_read(reg, value);
  }
}

uint8_t regs_writable(uint8_t reg) {
  return reg >= MCG_REG_MODE && reg < MCG_REG_COUNT && k_access[reg - 1u] != MCG_RO;
}

static uint8_t in_range(int16_t v, int16_t lo, int16_t hi) { return v >= lo && v <= hi; }

int16_t regs_min(uint8_t reg) { return k_min[reg - 1u]; }
int16_t regs_max(uint8_t reg) { return k_max[reg - 1u]; }

uint8_t regs_staging(uint8_t reg) {
  return (uint8_t)(reg == MCG_REG_COMMIT || (regs_writable(reg) && k_access[reg - 1u] == MCG_RS));
}

/* The writer the shadow set belongs to now, or 0 (core.h: MCG_WRITER_*). */
static uint8_t set_owner(void) { return g_seq_owns_set ? MCG_WRITER_SEQ : control_owner(); }

static uint8_t owned_by_another(uint8_t writer) {
  MCG_SLOW uint8_t owner = set_owner();
  return (uint8_t)(owner != 0 && owner != writer);
}

uint8_t regs_write(uint8_t reg, int16_t v) { return regs_write_by(MCG_WRITER_LINK, reg, v); }

uint8_t regs_write_by(uint8_t writer, uint8_t reg, int16_t v) {
  if (reg == MCG_REG_COMMIT && v == 1) { /* first: the commit's pass and the next update share a tick */
    return owned_by_another(writer) ? MCG_ST_BUSY : control_commit();
  }
  if (reg < MCG_REG_MODE || reg >= MCG_REG_COUNT) { /* the table has a row for every id between */
    return MCG_ST_BAD_REG;
  }
  if (!regs_writable(reg)) {
    return MCG_ST_READ_ONLY;
  }
  if (!in_range(v, k_min[reg - 1u], k_max[reg - 1u])) {
    return MCG_ST_RANGE;
  }
  if (regs_staging(reg) && owned_by_another(writer)) {
    return MCG_ST_BUSY;
  }
  switch (reg) {
    case MCG_REG_MODE:
      g_ctl_shadow.mode = (uint8_t)v;
      break;
    case MCG_REG_RPM_CMD:
      g_rpm_cmd = v;
      control_set_rpm_cmd(v);
      break;
    case MCG_REG_DUTY:
      if (g_mode != MCG_MODE_OPEN) {
        return MCG_ST_OWNED;
      }
      if (!in_range(v, g_duty_min, g_duty_max)) {
        return MCG_ST_RANGE;
      }
      g_duty_set = v;
      break;
    case MCG_REG_DUTY_STEP:
      g_duty_step = v;
      break;
    case MCG_REG_DUTY_BIAS:
      g_ctl_shadow.duty_bias = v;
      break;
    case MCG_REG_KP:
      g_ctl_shadow.kp = v;
      break;
    case MCG_REG_B0:
      g_ctl_shadow.b0 = v;
      break;
    case MCG_REG_B1:
      g_ctl_shadow.b1 = v;
      break;
    case MCG_REG_B2:
      g_ctl_shadow.b2 = v;
      break;
    case MCG_REG_COEF_FRAC:
      g_ctl_shadow.coef_frac = (uint8_t)v;
      break;
    case MCG_REG_DUTY_MIN: /* duty_min <= duty_max is checked by the commit, on the whole set */
      g_ctl_shadow.duty_min = v;
      break;
    case MCG_REG_DUTY_MAX:
      g_ctl_shadow.duty_max = v;
      break;
    case MCG_REG_SERVICE_MS:
      g_service_ms = (uint8_t)v;
      break;
    case MCG_REG_LOG_INTERVAL:
      return logger_set_interval((uint8_t)v);
    case MCG_REG_STREAM:
      g_stream_on = (uint8_t)v;
      break;
    case MCG_REG_CLUTCH:
      g_clutch_on = (uint8_t)(v == MCG_CLUTCH_ENGAGED);
      hal_clutch_write(g_clutch_on);
      break;
    case MCG_REG_LOAD:
      g_load_on = (uint8_t)v;
      hal_load_write(g_load_on);
      break;
    case MCG_REG_SEQ_STATE:
      return seq_set_state((uint8_t)v);
    case MCG_REG_RX_ERRORS:
      g_rx_errors = 0;
      break;
    case MCG_REG_TX_DROPS:
      g_tx_drops = 0;
      break;
    case MCG_REG_COMMIT: /* 0 discards (1 commits, above) */
      control_discard();
      break;
    case MCG_REG_EXC_RUN:
      return excite_set_run((uint8_t)v);
    default: /* the excitation's settings: they act at the next start (exc_run 1) */
      if (g_exc_run) {
        return MCG_ST_BUSY;
      }
      excite_set(reg, v);
      break;
  }
  if (k_access[reg - 1u] == MCG_RS) {
    control_staged(writer);
  }
  return MCG_ST_OK;
}

uint8_t regs_apply(uint8_t reg, int16_t v) {
  MCG_SLOW uint8_t st;
  if (!regs_writable(reg) || k_access[reg - 1u] != MCG_RS) {
    return regs_write_by(MCG_WRITER_KEYPAD, reg, v);
  }
  if (owned_by_another(MCG_WRITER_KEYPAD)) {
    return MCG_ST_BUSY;
  }
  control_discard();
  st = regs_write_by(MCG_WRITER_KEYPAD, reg, v);
  if (st != MCG_ST_OK) {
    return st;
  }
  return control_commit();
}
