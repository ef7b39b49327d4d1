/* A quadrature encoder on D2 (A, INT0) and D3 (B, INT1), decoded x4 in their interrupts.
   HFW_ENCODER_COUNTS_PER_REV is the motor shaft's counts per turn after x4 decoding. */
#include <avr/interrupt.h>
#include <avr/io.h>

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

int64_t position_latch(uint64_t now_us, uint16_t* status) {
    (void)now_us; /* edges come only when the shaft turns: an encoder is never stale */
    cli();
    const int32_t latched = counts;
    const uint8_t jump = jumped;
    jumped = 0;
    sei();
    *status = jump ? HFW_STATUS_ENCODER_JUMP : 0u;
    return (int64_t)HFW_POSITION_SIGN * latched;
}

float position_counts_per_meter(void) {
    return (float)(HFW_ENCODER_COUNTS_PER_REV / (2.0 * HFW_PI * HFW_HANDLE_M_PER_MOTOR_RAD));
}
