/* The handle's position sensor, read in the background: the magnetoresistive sensor on A2
   (position_mr.c) or a quadrature encoder on D2/D3 (position_quadrature.c), chosen by the
   build (HAPTICD_FIRMWARE_SENSOR). Counts are signed by HFW_POSITION_SIGN and zero where the
   handle was at power-up: start the board with the handle at its centre. */
#ifndef HFW_BOARD_POSITION_H
#define HFW_BOARD_POSITION_H

#include <stdint.h>

/* Starts the sensor and waits for its first reading, which becomes the zero. */
void position_init(void);

/* The latest counts, latched at now_us; *status gets HFW_STATUS_ENCODER_STALE when the
   sensor has given no new reading for longer than it should, HFW_STATUS_ENCODER_JUMP when it
   saw an impossible step since the last latch. */
int64_t position_latch(uint64_t now_us, uint16_t* status);

/* The counts per metre of handle travel the identity reports. */
float position_counts_per_meter(void);

#endif
