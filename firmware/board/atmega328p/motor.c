#include "motor.h"

#include <avr/io.h>

void motor_init(void) {
    PORTD &= (uint8_t)~_BV(PD5);
    DDRD |= _BV(PD5);
    PORTB &= (uint8_t)~_BV(PB0);
    DDRB |= _BV(PB0);
    OCR0B = 0;
    TCCR0A = _BV(WGM01) | _BV(WGM00); /* fast PWM, OC0B disconnected until a duty is set */
    TCCR0B = _BV(CS00);               /* F_CPU / 1: 62.5 kHz */
}

void motor_set(uint16_t duty, uint8_t direction) {
    /* Off first whenever the direction changes: the old duty must never drive the new way,
       not even for the instructions between the two writes. */
    const uint8_t reversing = ((PORTB & _BV(PB0)) != 0) != (direction != 0);
    if (duty == 0 || reversing) {
        TCCR0A &= (uint8_t)~_BV(COM0B1); /* the pin reads PORTD5: low */
        OCR0B = 0;
    }
    if (direction) {
        PORTB |= _BV(PB0);
    } else {
        PORTB &= (uint8_t)~_BV(PB0);
    }
    if (duty == 0) return;
    OCR0B = (uint8_t)((duty > 256u ? 256u : duty) - 1u);
    TCCR0A |= _BV(COM0B1); /* non-inverting fast PWM: high for OCR0B + 1 of 256 counts */
}
