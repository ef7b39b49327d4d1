/* The firmware's 64-bit microsecond clock from power-up (docs/protocol.md section 2):
   Timer1 counting F_CPU / 8 (0.5 us at 16 MHz), extended by its overflows. And the period's
   schedule on the same timer: compare B starts the position reading that completes at the
   period boundary, compare A marks the boundary (and wakes the main loop for the watchdog). */
#ifndef HFW_BOARD_CLOCK_H
#define HFW_BOARD_CLOCK_H

#include <stdint.h>

void clock_init(void);
uint64_t clock_now_us(void);

/* Starts the period's schedule: boundaries every HFW_PERIOD_US from now, each reading
   started lead_us before its boundary (position_lead_us()). */
void clock_start_periods(uint16_t lead_us);

/* The next period's reading: when it will start (us) and its number (*epoch; the readings
   the clock starts are numbered from 1, wrapping at 256). */
uint64_t clock_next_sample(uint8_t* epoch);

/* Called by the clock's interrupt right after it started reading number `epoch`, which
   completes as position_readings() reaches `reading` (paced.c sends a sample's front then). */
void clock_on_sample(uint8_t epoch, uint8_t reading);

#endif
