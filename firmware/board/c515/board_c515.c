/* board_c515.c: hal.h for the SAB 80C515 on the EMAC board (constants in board_c515.h). */
#include "board_c515.h"

#include <sab80515.h> /* T2CON, CRCL/H, CCEN, CCL1/H, IRCON.TF2, ADCON.BD, P4, TH0/TL0 */
#include <stdint.h>   /* uint8_t, uint16_t, int16_t */

#include "hal.h"          /* the seam implemented here */
#include "mcg_protocol.h" /* MCG_BOARD_C515, MCG_KEY_NONE */
#include "uart_mcs51.h"   /* uart_init */

static volatile uint8_t MCG_XDATA MCG_AT(C515_LCD_CMD_XADDR) s_lcd_cmd;
static volatile uint8_t MCG_XDATA MCG_AT(C515_LCD_DATA_XADDR) s_lcd_data;
static volatile uint8_t MCG_XDATA MCG_AT(C515_KEY_XADDR) s_key_port;

/* Keypad encoder code -> key (0..9, 0x0A..0x0F = A..F), row by row as the 4 x 4 pad is wired. */
static MCG_CODE uint8_t s_key_map[16] = {0x01, 0x02, 0x03, 0x0A, 0x04, 0x05, 0x06, 0x0B,
                                         0x07, 0x08, 0x09, 0x0C, 0x0E, 0x00, 0x0F, 0x0D};

static volatile uint8_t s_ticks;
static volatile uint16_t s_count_at_tick; /* Timer 0 pulse count latched at the last tick */
static uint16_t s_count_taken;            /* the latch value at the last hal_ticks_take */

uint8_t hal_board_id(void) { return MCG_BOARD_C515; }

/* Timer 2 overflow: latch the encoder count, count the tick. */
void board_tick_isr(void) MCG_ISR(5) {
  uint8_t hi;
  uint8_t lo;
  TF2 = 0; /* the 80515 does not clear it in hardware */
  C515_ENCODER_READ(hi, lo);
  s_count_at_tick = (uint16_t)((uint16_t)hi << 8 | lo);
  if (s_ticks != 255u) {
    ++s_ticks;
  }
}

static void lcd_wait(void) {
  uint8_t n = C515_LCD_BUSY_POLLS;
  while ((s_lcd_cmd & C515_LCD_BUSY) && --n) {
  }
}

static void lcd_command(uint8_t c) {
  lcd_wait();
  s_lcd_cmd = c;
}

void hal_init(void) {
  s_ticks = 0;
  s_count_at_tick = 0;
  s_count_taken = 0;
  P4 &= (uint8_t) ~(C515_P4_DIR | C515_P4_CLUTCH | C515_P4_LOAD);
  P1_1 = 0;
  TMOD = 0x05; /* Timer 0: 16-bit counter on T0 */
  TH0 = 0;
  TL0 = 0;
  TR0 = 1;
  CRCH = (uint8_t)(C515_T2_RELOAD >> 8);
  CRCL = (uint8_t)(C515_T2_RELOAD & 0xFFu);
  TH2 = CRCH;
  TL2 = CRCL;
  CCEN = 0; /* duty 0: compare off, P1.1 low */
  T2CON = C515_T2CON;
  ET2 = 1;
  ADCON |= 0x80; /* BD: baud rate generator */
  PCON |= 0x80;  /* SMOD: 9600 baud at 12 MHz */
  uart_init();
  EA = 1;
  /* The HD44780 needs more than 15 ms after power-up before its first command. */
  while (s_ticks < C515_LCD_POWER_UP_MS) {
  }
  lcd_command(0x38); /* 8-bit bus, 2 lines */
  lcd_command(0x0C); /* display on, no cursor */
  lcd_command(0x01); /* clear */
  lcd_command(0x06); /* increment */
  EA = 0;
  s_ticks = 0;
  s_count_taken = s_count_at_tick;
  EA = 1;
}

uint8_t hal_ticks_take(uint16_t* pulses) {
  uint8_t n;
  uint16_t count;
  EA = 0;
  n = s_ticks;
  s_ticks = 0;
  count = s_count_at_tick;
  EA = 1;
  *pulses = (uint16_t)(count - s_count_taken);
  s_count_taken = count;
  return n;
}

void hal_pwm_write(int16_t duty_permille) {
  /* CC1 = 0x10000 - |duty|: that is -duty for duty > 0 and duty itself (as u16) for duty < 0. */
  uint16_t cc = (uint16_t)duty_permille;
  if (duty_permille < 0) {
    P4 |= C515_P4_DIR;
  } else {
    P4 &= (uint8_t)~C515_P4_DIR;
    cc = (uint16_t)(0u - cc);
  }
  if (cc == 0) {
    CCEN &= (uint8_t)~C515_CCEN_CC1_MASK;
    P1_1 = 0;
    return;
  }
  CCH1 = (uint8_t)(cc >> 8);
  CCL1 = (uint8_t)(cc & 0xFFu); /* the low byte write takes the new value */
  CCEN |= C515_CCEN_CC1;
}

void hal_clutch_write(uint8_t on) {
  if (on) {
    P4 |= C515_P4_CLUTCH;
  } else {
    P4 &= (uint8_t)~C515_P4_CLUTCH;
  }
}

void hal_load_write(uint8_t on) {
  if (on) {
    P4 |= C515_P4_LOAD;
  } else {
    P4 &= (uint8_t)~C515_P4_LOAD;
  }
}

uint8_t hal_key_read(void) {
  uint8_t k = s_key_port;
  if (!(k & C515_KEY_AVAILABLE)) {
    return MCG_KEY_NONE;
  }
  return s_key_map[k & 0x0Fu];
}

void hal_lcd_write(uint8_t row, const char* text16) {
  uint8_t i;
  lcd_command(row ? 0xC0 : 0x80); /* DDRAM address of the row */
  for (i = 0; i < 16u && text16[i]; ++i) {
    lcd_wait();
    s_lcd_data = (uint8_t)text16[i];
  }
}
