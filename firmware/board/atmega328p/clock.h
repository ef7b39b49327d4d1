/* The firmware's 64-bit microsecond clock from power-up (docs/protocol.md section 2):
   Timer1 counting F_CPU / 8 (0.5 us at 16 MHz), extended by its overflows. And the period's
   schedule on the same timer, once a period: compare A starts the period (a paced sample's
   front goes out, and the main loop wakes to check the command watchdog), compare B starts
   the position reading front_lead_us later (so that its counts are in as the front's last
   bytes leave). */
#ifndef HFW_BOARD_CLOCK_H
#define HFW_BOARD_CLOCK_H

#include <stdint.h>

void clock_init(void);
uint64_t clock_now_us(void);

/* Starts the schedule: a period every HFW_PERIOD_US, its reading front_lead_us after its
   start. */
void clock_start_periods(uint16_t front_lead_us);

/* The next period that has not started: when its reading will start (us), and its number
   (*period, counted from 1 and wrapping at 256). */
uint64_t clock_next_period(uint8_t* period);

/* Called by the clock's interrupts (paced.c): at the start of period `period`, and when its
   reading has started, which completes as position_readings() reaches `reading`. */
void clock_on_period(uint8_t period);
void clock_on_sample(uint8_t period, uint8_t reading);

#endif
