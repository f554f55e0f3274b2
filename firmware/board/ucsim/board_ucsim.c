/* board_ucsim.c: hal.h for s51's 80C517 model (see board_ucsim.h). */
#include "board_ucsim.h"

#include <8051.h>   /* TMOD, TH0, TL0, TH1, PCON, TR0, TR1, ET0, EA */
#include <stdint.h> /* uint8_t, int16_t */

#include "hal.h"          /* the seam implemented here */
#include "mcg_protocol.h" /* MCG_BOARD_UCSIM, MCG_KEY_NONE */
#include "uart_mcs51.h"   /* uart_init */

static volatile uint8_t MCG_XDATA MCG_AT(SIM_IO_XADDR) s_io[SIM_KEY_QUEUE + SIM_KEY_QUEUE_MAX];
static uint8_t MCG_XDATA s_key_next;     /* next queued key */
static uint8_t MCG_XDATA s_key_released; /* 1: the last sample presented a queued key */
static volatile uint8_t s_ticks;
static int16_t s_duty;
static int16_t s_pulse_acc; /* test encoder: duty-ticks not yet turned into pulses */

uint8_t hal_board_id(void) { return MCG_BOARD_UCSIM; }

void board_tick_isr(void) MCG_ISR(1) {
  TH0 = SIM_T0_RELOAD_H;
  TL0 = SIM_T0_RELOAD_L;
  if (s_ticks != 255u) {
    ++s_ticks;
  }
}

void hal_init(void) {
  uint8_t i;
  for (i = 0; i < SIM_KEY_QUEUE; ++i) {
    s_io[i] = ' ';
  }
  s_io[0] = 0;
  s_io[1] = 0;
  s_io[2] = 0;
  s_io[3] = 0;
  s_io[4] = MCG_KEY_NONE;
  s_io[5] = 0;
  s_key_next = 0;
  s_key_released = 0;
  s_duty = 0;
  s_pulse_acc = 0;
  s_ticks = 0;
  TMOD = 0x21;  /* Timer 1 mode 2 (baud), Timer 0 mode 1 (tick) */
  PCON |= 0x80; /* SMOD */
  TH1 = 0xF9;
  TL1 = 0xF9;
  TH0 = SIM_T0_RELOAD_H;
  TL0 = SIM_T0_RELOAD_L;
  TR1 = 1;
  TR0 = 1;
  ET0 = 1;
  uart_init();
  EA = 1;
}

uint8_t hal_ticks_take(uint16_t* pulses) {
  uint8_t n;
  uint16_t p = 0;
  uint8_t i;
  EA = 0;
  n = s_ticks;
  s_ticks = 0;
  EA = 1;
  for (i = 0; i < n; ++i) {
    s_pulse_acc += s_duty < 0 ? -s_duty : s_duty;
    while (s_pulse_acc >= SIM_PULSES_DIVISOR) {
      s_pulse_acc -= SIM_PULSES_DIVISOR;
      ++p;
    }
  }
  *pulses = p;
  return n;
}

void hal_pwm_write(int16_t duty_permille) {
  s_duty = duty_permille;
  s_io[0] = (uint8_t)((uint16_t)duty_permille & 0xFFu);
  s_io[1] = (uint8_t)((uint16_t)duty_permille >> 8);
}

void hal_clutch_write(uint8_t on) { s_io[2] = on; }

void hal_load_write(uint8_t on) { s_io[3] = on; }

uint8_t hal_key_read(void) {
  if (s_key_released) {
    s_key_released = 0;
    return MCG_KEY_NONE;
  }
  if (s_key_next < s_io[5] && s_key_next < SIM_KEY_QUEUE_MAX) {
    s_key_released = 1;
    return s_io[SIM_KEY_QUEUE + s_key_next++];
  }
  return s_io[4];
}

void hal_lcd_write(uint8_t row, const char* text16) {
  uint8_t base = row ? 0x20u : 0x10u;
  uint8_t i;
  for (i = 0; i < 16u && text16[i]; ++i) {
    s_io[base + i] = (uint8_t)text16[i];
  }
}
