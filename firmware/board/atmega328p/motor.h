/* The motor driver: PWM on D5 (Timer0's OC0B, 62.5 kHz fast PWM) and the direction on D8
   (PB0), as the Hapkit 3.0 board wires them. */
#ifndef HFW_BOARD_MOTOR_H
#define HFW_BOARD_MOTOR_H

#include <stdint.h>

/* Pins low, the output off: zero force from the first instruction after reset. */
void motor_init(void);

/* duty in 1/256 of the period, 0..256 (0: the pin held low, no PWM spike; 256: always
   high); direction 1 drives D8 high. */
void motor_set(uint16_t duty, uint8_t direction);

#endif
