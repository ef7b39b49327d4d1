/* The Hapkit's magnetoresistive angle sensor on A2: ADC conversions run back to back
   (prescaler 128: a 125 kHz ADC clock, within the 50-200 kHz that full 10-bit accuracy needs;
   13 cycles, 104 us each) and each one is unwrapped over the sensor's flips in the
   interrupt, so no flip is missed between two latches. */
#include <avr/interrupt.h>
#include <avr/io.h>

#include "hfw_config.h"
#include "hfw_kinematics.h"
#include "hfw_protocol.h"
#include "position.h"

static struct hfw_mr_sensor sensor;
static volatile int32_t unwrapped;
static volatile uint8_t conversions;
static int32_t zero;
static uint8_t latched_conversions; /* `conversions` at the last latch that saw a new one */
static uint64_t fresh_us;           /* the time of that latch */

/* Two conversions' time and some: no new reading for this long means the ADC stopped. */
#define STALE_AFTER_US 250u

ISR(ADC_vect) {
    unwrapped = hfw_mr_sensor_update(&sensor, (int16_t)ADC);
    ++conversions;
}

void position_init(void) {
    hfw_mr_sensor_init(&sensor, HFW_MR_COUNTS_PER_FLIP, HFW_MR_FLIP_THRESHOLD);
    ADMUX = _BV(REFS0) | 2u; /* AVcc reference, channel 2 (A2) */
    DIDR0 = _BV(ADC2D);      /* no digital input buffer on A2 */
    ADCSRB = 0;              /* free running */
    ADCSRA = _BV(ADEN) | _BV(ADSC) | _BV(ADATE) | _BV(ADIE) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0);
    sei();
    while (conversions < 2u) {
    } /* the first conversion after enabling takes 25 cycles: use the second */
    cli();
    zero = unwrapped;
    latched_conversions = conversions;
    sei();
}

int64_t position_latch(uint64_t now_us, uint16_t* status) {
    cli();
    const int32_t counts = unwrapped;
    const uint8_t seen = conversions;
    sei();
    *status = 0;
    if (seen != latched_conversions) {
        latched_conversions = seen;
        fresh_us = now_us;
    } else if (now_us - fresh_us > STALE_AFTER_US) {
        *status = HFW_STATUS_ENCODER_STALE;
    }
    return (int64_t)HFW_POSITION_SIGN * (int64_t)(counts - zero);
}

float position_counts_per_meter(void) { return (float)HFW_COUNTS_PER_METER; }
