/* menu.c: the keypad and the 2-line LCD as a state machine, sampled every service period.
 *
 * Main screen   line 1 measured: "  421 rpm PID CL" (speed, mode, clutch C, load L)
 *               line 2 command:  "c 420  d  37.5% " (or "open" in open loop; duty in %)
 *   A / B       up / down: duty by the duty step (open loop) or the command by 10 rpm; repeats
 *               every service period while held, so the service period sets the ramp rate
 *   C menu   D dump the RAM log   E stream on/off   F record the RAM log
 *   0 stop (open loop, duty 0)   1 clutch on/off   2 load on/off
 * Menu          line 1 the parameter, line 2 its value: A next, B previous, D edit, C back
 * Edit          digits, F decimal point (gains), E sign, C delete (on empty: cancel), D store.
 *               Gains are typed in decimal (e.g. 2.5) and stored as round(value * 2^F); every
 *               value goes through regs_apply, so the keypad obeys the same ranges as the link,
 *               and a controller register changes as one commit (refused: "refused" and the code).
 * The report's board could not take Kp from the keypad; here Kp is an item like any other. */
#include "core.h"
#include "hal.h" /* hal_key_read, hal_lcd_write */

char MCG_XDATA g_lcd[2][17];

#define KEY_A 0x0Au
#define KEY_B 0x0Bu
#define KEY_C 0x0Cu
#define KEY_D 0x0Du
#define KEY_E 0x0Eu
#define KEY_F 0x0Fu

#define KIND_INT 0u
#define KIND_COEF 1u /* Q(F) gain shown and typed in decimal */
#define KIND_MODE 2u

#define SCREEN_MAIN 0u
#define SCREEN_BROWSE 1u
#define SCREEN_EDIT 2u

#define ENTRY_MAX 8u
#define RPM_KEY_STEP 10

/* The menu from the keypad column of MCG_REGISTERS, indexed by id - 1: each register's position
 * in the menu (0: not in it), its label, and how its value is shown and typed (from its unit). */
#define MENU_POS(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) MCG_KEY_POS(keypad),
#define MENU_LABEL(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) MCG_KEY_LABEL(keypad),
#define MENU_KIND(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) \
  (unit) == MCG_UNIT_GAIN ? KIND_COEF : (unit) == MCG_UNIT_MODE ? KIND_MODE : KIND_INT,
#define MENU_COUNT(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) +(MCG_KEY_POS(keypad) != 0u)
static MCG_CODE uint8_t k_item_pos[] = {MCG_REGISTERS(MENU_POS)};
static MCG_CODE char k_item_label[][17] = {MCG_REGISTERS(MENU_LABEL)};
static MCG_CODE uint8_t k_item_kind[] = {MCG_REGISTERS(MENU_KIND)};
#define ITEM_COUNT ((uint8_t)(0u MCG_REGISTERS(MENU_COUNT)))

static MCG_CODE char s_mode_names[MCG_MODE_COUNT][4] = {"OL ", "P  ", "PI ", "PID"};

static MCG_XDATA uint8_t s_screen;
static MCG_XDATA uint8_t s_item;     /* position in the menu, from 0 */
static MCG_XDATA uint8_t s_item_reg; /* the register shown there */
static MCG_XDATA uint8_t s_last_key;
static MCG_XDATA uint8_t s_status; /* status of the last store, shown until the next key */
static char MCG_XDATA s_entry[ENTRY_MAX + 1];
static MCG_XDATA uint8_t s_entry_len;

/* The register at menu position s_item (the positions are 1..ITEM_COUNT, each once). */
static void select_item(uint8_t item) {
  MCG_SLOW uint8_t i;
  s_item = item;
  for (i = 0; i < MCG_REG_COUNT - 1u; ++i) {
    if (k_item_pos[i] == (uint8_t)(item + 1u)) {
      s_item_reg = (uint8_t)(i + 1u);
    }
  }
}

void menu_init(void) {
  s_screen = SCREEN_MAIN;
  select_item(0);
  s_last_key = MCG_KEY_NONE;
  s_status = MCG_ST_OK;
  s_entry_len = 0;
  s_entry[0] = 0;
}

/* Writes v right-aligned into width characters at dst (no terminator). */
static void put_int(char MCG_XDATA* dst, int32_t v, uint8_t width) MCG_REENTRANT {
  uint8_t neg = v < 0;
  uint32_t m = neg ? (uint32_t)-v : (uint32_t)v;
  uint8_t i = width;
  do {
    dst[--i] = (char)('0' + m % 10u);
    m /= 10u;
  } while (m != 0 && i > 0);
  if (neg && i > 0) {
    dst[--i] = '-';
  }
  while (i > 0) {
    dst[--i] = ' ';
  }
}

/* Writes v / 10^decimals with that many decimals, right-aligned in width characters. */
static void put_fixed(char MCG_XDATA* dst, int32_t v, uint8_t decimals, uint8_t width) MCG_REENTRANT {
  uint32_t m = v < 0 ? (uint32_t)-v : (uint32_t)v;
  uint8_t i = width;
  uint8_t d;
  for (d = 0; d < decimals; ++d) {
    dst[--i] = (char)('0' + m % 10u);
    m /= 10u;
  }
  dst[--i] = '.';
  do {
    dst[--i] = (char)('0' + m % 10u);
    m /= 10u;
  } while (m != 0 && i > 0);
  if (v < 0 && i > 0) {
    dst[--i] = '-';
  }
  while (i > 0) {
    dst[--i] = ' ';
  }
}

static void clear_line(uint8_t row) {
  MCG_SLOW uint8_t i;
  for (i = 0; i < 16; ++i) {
    g_lcd[row][i] = ' ';
  }
  g_lcd[row][16] = 0;
}

static void put_text(uint8_t row, uint8_t col, const char* text) {
  while (*text && col < 16) {
    g_lcd[row][col++] = *text++;
  }
}

/* A gain in Q(F) to thousandths, rounded half away from zero. */
static int32_t coef_to_milli(int16_t raw) MCG_REENTRANT {
  int32_t m = (int32_t)raw * 1000;
  int32_t half = g_coef_frac > 0 ? ((int32_t)1 << (g_coef_frac - 1)) : 0;
  if (m >= 0) {
    return (m + half) >> g_coef_frac;
  }
  return -((-m + half) >> g_coef_frac);
}

static void show_value(uint8_t row) {
  MCG_SLOW int16_t v = 0;
  MCG_SLOW uint8_t kind = k_item_kind[s_item_reg - 1u];
  regs_read(s_item_reg, &v);
  if (kind == KIND_COEF) {
    put_fixed(g_lcd[row], coef_to_milli(v), 3, 12);
  } else if (kind == KIND_MODE) {
    put_int(g_lcd[row], v, 2);
    put_text(row, 3, s_mode_names[(uint8_t)v]);
  } else {
    put_int(g_lcd[row], v, 6);
  }
}

void menu_refresh(void) {
  clear_line(0);
  clear_line(1);
  if (s_screen == SCREEN_MAIN) {
    put_int(g_lcd[0], control_rpm(), 5);
    put_text(0, 5, " rpm ");
    put_text(0, 10, s_mode_names[g_mode]);
    g_lcd[0][14] = g_clutch_on ? 'C' : '-';
    g_lcd[0][15] = g_load_on ? 'L' : '-';
    if (g_mode == MCG_MODE_OPEN) {
      put_text(1, 0, "open");
    } else {
      g_lcd[1][0] = 'c';
      put_int(g_lcd[1] + 1, g_rpm_cmd, 4);
    }
    put_text(1, 5, "  d");
    put_fixed(g_lcd[1] + 8, g_duty_out, 1, 6);
    g_lcd[1][14] = '%';
  } else {
    put_text(0, 0, k_item_label[s_item_reg - 1u]);
    if (s_screen == SCREEN_EDIT) {
      put_text(1, 0, s_entry);
      g_lcd[1][s_entry_len] = '_';
    } else if (s_status != MCG_ST_OK) {
      put_text(1, 0, "refused");
      put_int(g_lcd[1] + 8, s_status, 3);
    } else {
      show_value(1);
    }
  }
  hal_lcd_write(0, g_lcd[0]);
  hal_lcd_write(1, g_lcd[1]);
}

/* Parses the entry: [-]digits[.digits]. Gains: round(value * 2^F), at most 3 decimals.
 * Returns MCG_ST_OK and *out, or MCG_ST_RANGE. */
static uint8_t parse_entry(uint8_t kind, int16_t* out) MCG_REENTRANT {
  uint8_t i = 0;
  uint8_t neg = 0;
  uint8_t decimals = 0;
  uint8_t seen_point = 0;
  uint8_t digits = 0;
  int32_t v = 0;
  if (s_entry_len > 0 && s_entry[0] == '-') {
    neg = 1;
    i = 1;
  }
  for (; i < s_entry_len; ++i) {
    if (s_entry[i] == '.') {
      seen_point = 1;
      continue;
    }
    v = v * 10 + (s_entry[i] - '0');
    ++digits;
    if (seen_point) {
      ++decimals;
    }
  }
  if (digits == 0) {
    return MCG_ST_RANGE;
  }
  if (kind == KIND_COEF) {
    for (; decimals < 3; ++decimals) {
      v *= 10;
    }
    /* v is thousandths; raw = round(v * 2^F / 1000), |raw| <= 32768 keeps v * 2^F in 32 bits */
    if (v > (int32_t)(32768000L >> g_coef_frac)) {
      return MCG_ST_RANGE;
    }
    v = (v * ((int32_t)1 << g_coef_frac) + 500) / 1000;
  }
  if (neg) {
    v = -v;
  }
  if (v > 32767 || v < -32768) {
    return MCG_ST_RANGE;
  }
  *out = (int16_t)v;
  return MCG_ST_OK;
}

static void entry_key(uint8_t key) {
  MCG_SLOW uint8_t kind = k_item_kind[s_item_reg - 1u];
  MCG_SLOW uint8_t i;
  MCG_SLOW int16_t v;
  if (key == KEY_D) {
    s_status = parse_entry(kind, &v);
    if (s_status == MCG_ST_OK) {
      s_status = regs_apply(s_item_reg, v);
    }
    s_screen = SCREEN_BROWSE;
    return;
  }
  if (key == KEY_C) {
    if (s_entry_len == 0) {
      s_screen = SCREEN_BROWSE;
    } else {
      s_entry[--s_entry_len] = 0;
    }
    return;
  }
  if (key == KEY_E) {
    if (s_entry_len > 0 && s_entry[0] == '-') {
      for (i = 0; i < s_entry_len; ++i) {
        s_entry[i] = s_entry[i + 1];
      }
      --s_entry_len;
    } else if (s_entry_len < ENTRY_MAX) {
      for (i = s_entry_len + 1; i > 0; --i) {
        s_entry[i] = s_entry[i - 1];
      }
      s_entry[0] = '-';
      ++s_entry_len;
    }
    return;
  }
  if (s_entry_len >= ENTRY_MAX) {
    return;
  }
  if (key == KEY_F) {
    /* one point, gains only, at most 3 decimals follow (checked as digits arrive) */
    for (i = 0; i < s_entry_len; ++i) {
      if (s_entry[i] == '.') {
        return;
      }
    }
    if (kind != KIND_COEF) {
      return;
    }
    s_entry[s_entry_len++] = '.';
  } else if (key <= 9u) {
    for (i = 0; i < s_entry_len && s_entry[i] != '.'; ++i) {
    }
    if (i < s_entry_len && (uint8_t)(s_entry_len - i) > 3u) {
      return;
    }
    s_entry[s_entry_len++] = (char)('0' + key);
  }
  s_entry[s_entry_len] = 0;
}

static void nudge(int8_t dir) {
  if (g_mode == MCG_MODE_OPEN) {
    MCG_SLOW int16_t d = (int16_t)(g_duty_set + dir * g_duty_step);
    if (d > g_duty_max) {
      d = g_duty_max;
    } else if (d < g_duty_min) {
      d = g_duty_min;
    }
    regs_write(MCG_REG_DUTY, d);
  } else {
    regs_write(MCG_REG_RPM_CMD, (int16_t)(g_rpm_cmd + dir * RPM_KEY_STEP));
  }
}

static void main_key(uint8_t key, uint8_t repeat) {
  if (key == KEY_A || key == KEY_B) {
    nudge(key == KEY_A ? 1 : -1);
    return;
  }
  if (repeat) {
    return;
  }
  switch (key) {
    case KEY_C:
      s_screen = SCREEN_BROWSE;
      s_status = MCG_ST_OK;
      break;
    case KEY_D:
      logger_dump_start();
      break;
    case KEY_E:
      regs_write(MCG_REG_STREAM, (int16_t)!g_stream_on);
      break;
    case KEY_F:
      logger_start();
      break;
    case 0:
      regs_apply(MCG_REG_MODE, MCG_MODE_OPEN);
      regs_write(MCG_REG_DUTY, g_duty_min > 0 ? g_duty_min : (g_duty_max < 0 ? g_duty_max : 0));
      break;
    case 1:
      regs_write(MCG_REG_CLUTCH, (int16_t)(g_clutch_on ? MCG_CLUTCH_ATTACHED : MCG_CLUTCH_ENGAGED));
      break;
    case 2:
      regs_write(MCG_REG_LOAD, (int16_t)!g_load_on);
      break;
    default:
      break;
  }
}

void menu_service(void) {
  MCG_SLOW uint8_t key = hal_key_read();
  MCG_SLOW uint8_t repeat = key == s_last_key;
  s_last_key = key;
  if (key == MCG_KEY_NONE) {
    return;
  }
  if (s_screen == SCREEN_MAIN) {
    main_key(key, repeat);
    if (repeat && key != KEY_A && key != KEY_B) {
      return;
    }
  } else if (repeat) {
    return;
  } else if (s_screen == SCREEN_BROWSE) {
    s_status = MCG_ST_OK;
    if (key == KEY_A) {
      select_item((uint8_t)((s_item + 1u) % ITEM_COUNT));
    } else if (key == KEY_B) {
      select_item((uint8_t)((s_item + ITEM_COUNT - 1u) % ITEM_COUNT));
    } else if (key == KEY_C) {
      s_screen = SCREEN_MAIN;
    } else if (key == KEY_D) {
      s_screen = SCREEN_EDIT;
      s_entry_len = 0;
      s_entry[0] = 0;
    }
  } else {
    entry_key(key);
  }
  menu_refresh();
}
