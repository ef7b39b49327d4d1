/* The handle's position sensor: the magnetoresistive sensor on A2 (position_mr.c) or a
   quadrature encoder on D2/D3 (position_quadrature.c), chosen by the build
   (HAPTICD_FIRMWARE_SENSOR). Counts are signed by HFW_POSITION_SIGN and zero where the handle
   was at power-up: start the board with the handle at its centre.

   A reading is taken on request (position_start) and by the clock once a period (clock.c);
   each carries the moment the sensor sampled it. */
#ifndef HFW_BOARD_POSITION_H
#define HFW_BOARD_POSITION_H

#include <stdint.h>

/* Starts the sensor and takes its first reading, which becomes the zero. */
void position_init(void);

/* How long a reading takes from position_start() to its result (us). */
uint16_t position_conversion_us(void);

/* From a reading's start to the moment the sensor samples (us): the sample's time_us. */
uint8_t position_sample_delay_us(void);

/* The period's reading, started by the clock's interrupt at the time it scheduled (start_us):
   the same as position_start() without reading the clock. */
uint8_t position_start_at(uint64_t start_us);

/* Starts a reading now, or right after the one under way. Returns the number of readings
   (position_readings()) once the first reading sampled at or after now has completed. */
uint8_t position_start(void);

/* Readings completed since power-up (wraps at 256). */
uint8_t position_readings(void);

/* The last completed reading's counts; *sampled_us is when the sensor sampled them, and
   *status has HFW_STATUS_ENCODER_JUMP when the sensor saw an impossible step since the
   reading before. */
int64_t position_last(uint64_t* sampled_us, uint16_t* status);

/* The counts per metre of handle travel the identity reports. */
float position_counts_per_meter(void);

#endif
