/* A quadrature encoder on D2 (A, INT0) and D3 (B, INT1), decoded x4 in their interrupts.
   HFW_ENCODER_COUNTS_PER_REV is the motor shaft's counts per turn after x4 decoding. The
   count is always current: a reading is the count at the moment it is asked for. */
#include <avr/interrupt.h>
#include <avr/io.h>

#include "clock.h"
#include "hfw_config.h"
#include "hfw_kinematics.h"
#include "hfw_protocol.h"
#include "position.h"

#ifndef HFW_ENCODER_COUNTS_PER_REV
#error "a quadrature build needs HFW_ENCODER_COUNTS_PER_REV in its config"
#endif

static volatile int32_t counts;
static volatile uint8_t channels; /* bit 1: A, bit 0: B */
static volatile uint8_t jumped;
static int32_t reading;
static uint64_t reading_us;
static uint8_t reading_jumped;
static volatile uint8_t readings;

static uint8_t read_channels(void) {
    const uint8_t pins = PIND;
    return (uint8_t)(((pins & _BV(PD2)) ? 2u : 0u) | ((pins & _BV(PD3)) ? 1u : 0u));
}

static void on_edge(void) {
    const uint8_t now = read_channels();
    const int8_t step = hfw_quadrature_step(channels, now);
    if (step == HFW_QUADRATURE_ILLEGAL) {
        jumped = 1;
    } else {
        counts += step;
    }
    channels = now;
}

ISR(INT0_vect) { on_edge(); }
ISR(INT1_vect) { on_edge(); }

void position_init(void) {
    DDRD &= (uint8_t) ~(_BV(PD2) | _BV(PD3));
    PORTD |= _BV(PD2) | _BV(PD3); /* pull-ups for open-collector encoders */
    channels = read_channels();
    EICRA = _BV(ISC10) | _BV(ISC00); /* any change on INT0 and INT1 */
    EIFR = _BV(INTF1) | _BV(INTF0);
    EIMSK = _BV(INT1) | _BV(INT0);
    sei();
}

uint16_t position_conversion_us(void) { return 0; }

uint8_t position_sample_delay_us(void) { return 0; }

uint8_t position_start(void) {
    const uint8_t sreg = SREG;
    cli();
    reading = counts;
    reading_jumped = jumped;
    jumped = 0;
    reading_us = clock_now_us();
    ++readings;
    SREG = sreg;
    return readings;
}

uint8_t position_start_at(uint64_t start_us) {
    (void)start_us; /* the count is current: its time is now */
    return position_start();
}

uint8_t position_readings(void) { return readings; }

int64_t position_last(uint64_t* sampled, uint16_t* status) {
    const uint8_t sreg = SREG;
    cli();
    const int32_t latched = reading;
    *sampled = reading_us;
    *status = reading_jumped ? HFW_STATUS_ENCODER_JUMP : 0u;
    SREG = sreg;
    return (int64_t)HFW_POSITION_SIGN * latched;
}

float position_counts_per_meter(void) {
    return (float)(HFW_ENCODER_COUNTS_PER_REV / (2.0 * HFW_PI * HFW_HANDLE_M_PER_MOTOR_RAD));
}
