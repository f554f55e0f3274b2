/* main.c (ucsim): the SIM image's entry point; the ISR prototypes must be visible here for SDCC. */
#include "board_ucsim.h" /* board_tick_isr */
#include "core.h"        /* core_init, core_poll */
#include "hal.h"         /* hal_init */
#include "uart_mcs51.h"  /* uart_isr */

void main(void) {
  hal_init();
  core_init();
  for (;;) {
    core_poll();
  }
}
