/* The firmware's 64-bit microsecond clock from power-up (docs/protocol.md section 2):
   Timer1 counting F_CPU / 8 (0.5 us at 16 MHz), extended by its overflows; its compare match
   wakes the main loop once a period. */
#ifndef HFW_BOARD_CLOCK_H
#define HFW_BOARD_CLOCK_H

#include <stdint.h>

void clock_init(void);
uint64_t clock_now_us(void);

#endif
