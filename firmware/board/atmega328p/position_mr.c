/* The Hapkit's magnetoresistive angle sensor on A2, one ADC conversion per reading (prescaler
   64: a 250 kHz ADC clock, a little above the 200 kHz that the last bit of 10 needs, for a
   reading in half the time: a 12.3 um count is finer than the sensor's noise). A conversion
   samples 1.5 ADC clocks (6 us) after it starts and completes 13 ADC clocks (52 us) after it
   starts; the interrupt unwraps each one over the sensor's flips. The clock
   starts one a period, so no flip is missed (the shaft turns less than a flip threshold in a
   millisecond below 8 m/s at the handle). */
#include <avr/interrupt.h>
#include <avr/io.h>

#include "clock.h"
#include "hfw_config.h"
#include "hfw_kinematics.h"
#include "position.h"

#define SAMPLE_AFTER_START_US 6u
#define CONVERSION_US 52u

static struct hfw_mr_sensor sensor;
static int32_t zero;
static volatile int32_t unwrapped;
static volatile uint64_t sampled_us;      /* of `unwrapped` */
static volatile uint64_t sampled_next_us; /* when the conversion under way sampled */
static volatile uint8_t readings;
static volatile uint8_t busy;
static volatile uint8_t restart; /* start another as soon as this one completes */

/* Called with `busy` just set, by its only owner: nothing else touches the conversion. */
static void start_conversion_at(uint64_t start_us) {
    sampled_next_us = start_us + SAMPLE_AFTER_START_US;
    ADCSRA |= _BV(ADSC);
}

static void start_conversion(void) { start_conversion_at(clock_now_us()); }

ISR(ADC_vect, ISR_NOBLOCK) {
    unwrapped = hfw_mr_sensor_update(&sensor, (int16_t)ADC);
    sampled_us = sampled_next_us;
    ++readings;
    if (restart) {
        restart = 0; /* busy stays set: the next conversion is this interrupt's */
        start_conversion();
    } else {
        busy = 0;
    }
}

void position_init(void) {
    hfw_mr_sensor_init(&sensor, HFW_MR_COUNTS_PER_FLIP, HFW_MR_FLIP_THRESHOLD);
    ADMUX = _BV(REFS0) | 2u; /* AVcc reference, channel 2 (A2) */
    DIDR0 = _BV(ADC2D);      /* no digital input buffer on A2 */
    ADCSRA = _BV(ADEN) | _BV(ADIE) | _BV(ADPS2) | _BV(ADPS1);
    sei();
    /* The first conversion after enabling initialises the ADC (25 ADC clocks): use the next. */
    for (uint8_t n = 0; n < 2u; ++n) {
        const uint8_t target = position_start();
        while (readings != target) {
        }
    }
    cli();
    zero = unwrapped;
    sei();
}

uint16_t position_conversion_us(void) { return CONVERSION_US; }

uint8_t position_sample_delay_us(void) { return SAMPLE_AFTER_START_US; }

/* Interrupts are off only for the flags: the USART's receive interrupt must never wait long
   (uart.h). A reading asked for while one is under way starts when that one is in. */
static uint8_t claim(uint8_t* target) {
    const uint8_t sreg = SREG;
    cli();
    *target = (uint8_t)(readings + 1u);
    const uint8_t was_busy = busy;
    if (was_busy) {
        restart = 1;
        ++*target;
    } else {
        busy = 1;
    }
    SREG = sreg;
    return !was_busy;
}

uint8_t position_start(void) {
    uint8_t target = 0;
    if (claim(&target)) start_conversion();
    return target;
}

uint8_t position_start_at(uint64_t start_us) {
    uint8_t target = 0;
    if (claim(&target)) start_conversion_at(start_us);
    return target;
}

uint8_t position_readings(void) { return readings; }

int64_t position_last(uint64_t* sampled, uint16_t* status) {
    const uint8_t sreg = SREG;
    cli();
    const int32_t counts = unwrapped;
    *sampled = sampled_us;
    SREG = sreg;
    *status = 0;
    return (int64_t)HFW_POSITION_SIGN * (int64_t)(counts - zero);
}

float position_counts_per_meter(void) { return (float)HFW_COUNTS_PER_METER; }
