#include "clock.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "hfw_config.h"
#include "position.h"

#if F_CPU != 16000000UL
#error "clock.c counts 0.5 us ticks: F_CPU must be 16 MHz"
#endif

#define TICKS_PER_US 2u
#define PERIOD_TICKS ((uint16_t)(TICKS_PER_US * HFW_PERIOD_US))

/* The microseconds at the last overflow: 65536 ticks are 32,768 us. Kept whole so that
   reading the clock costs an add, not a 64-bit shift (a library call on the AVR). */
static volatile uint64_t overflow_us;

static volatile uint8_t period;          /* the number of the last period started */
static volatile uint64_t next_sample_us; /* when the next period's reading starts */

/* Blocking: a 64-bit add that clock_now_us() must never see half done. */
ISR(TIMER1_OVF_vect) { overflow_us += 32768u; }

/* A period starts: its paced sample's front goes out (paced.c), and the main loop wakes and
   checks the command watchdog (docs/protocol.md 5.4: at the latest at the first period start
   after the timeout). Interruptible (ISR_NOBLOCK), as compare B's and the ADC's are: the
   USART's receive interrupt must run within two byte times (10 us) of a byte, or the next one
   overruns its two-byte buffer. */
ISR(TIMER1_COMPA_vect, ISR_NOBLOCK) {
    OCR1A += PERIOD_TICKS;
    const uint8_t sreg = SREG;
    cli();
    const uint8_t started = (uint8_t)(period + 1u);
    period = started;
    next_sample_us += HFW_PERIOD_US;
    SREG = sreg;
    clock_on_period(started);
}

/* The period's reading (which also keeps the MR sensor's flips counted). */
ISR(TIMER1_COMPB_vect, ISR_NOBLOCK) {
    OCR1B += PERIOD_TICKS;
    const uint8_t sreg = SREG;
    cli(); /* a 64-bit value compare A writes: never read half of it */
    const uint64_t start_us = next_sample_us;
    const uint8_t this_period = period;
    SREG = sreg;
    clock_on_sample(this_period, position_start_at(start_us));
}

void clock_init(void) {
    TCCR1A = 0;
    TCCR1B = _BV(CS11); /* F_CPU / 8 */
    TIMSK1 = _BV(TOIE1);
}

void clock_start_periods(uint16_t front_lead_us) {
    const uint8_t sreg = SREG;
    cli();
    const uint16_t now = TCNT1;
    const uint16_t start = (uint16_t)(now + PERIOD_TICKS);
    OCR1A = start;
    OCR1B = (uint16_t)(start + TICKS_PER_US * front_lead_us);
    /* the reading of the period before the first: compare A adds a period as it starts */
    next_sample_us = clock_now_us() + (uint16_t)(OCR1B - now) / TICKS_PER_US - HFW_PERIOD_US;
    TIFR1 = _BV(OCF1A) | _BV(OCF1B);
    TIMSK1 |= _BV(OCIE1A) | _BV(OCIE1B);
    SREG = sreg;
}

uint64_t clock_next_period(uint8_t* next) {
    const uint8_t sreg = SREG;
    cli();
    const uint64_t at_us = next_sample_us + HFW_PERIOD_US;
    *next = (uint8_t)(period + 1u);
    SREG = sreg;
    return at_us;
}

uint64_t clock_now_us(void) {
    const uint8_t sreg = SREG;
    cli();
    const uint16_t ticks = TCNT1;
    uint64_t base_us = overflow_us;
    if ((TIFR1 & _BV(TOV1)) && ticks < 0x8000u) base_us += 32768u; /* wrapped, ISR not yet run */
    SREG = sreg;
    return base_us + (ticks >> 1);
}
