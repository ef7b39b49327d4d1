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

ISR(TIMER1_OVF_vect) { overflow_us += 32768u; }

/* The boundary: only wakes the main loop, which checks the command watchdog
   (docs/protocol.md 5.4: at the latest at the first period boundary after the timeout) and
   sends a paced sample once its reading is in. */
ISR(TIMER1_COMPA_vect) { OCR1A += PERIOD_TICKS; }

static volatile uint64_t next_sample_us; /* when compare B next starts a reading */
static volatile uint8_t sample_epoch;    /* the number of the last reading it started */

/* The reading that completes at the boundary (and keeps the MR sensor's flips counted).
   Interruptible (ISR_NOBLOCK), as the ADC's is: the USART's receive interrupt must run within
   two byte times (10 us) of a byte, or the next one overruns its two-byte buffer. The short
   ones (the overflow's 64-bit add, compare A) block. */
ISR(TIMER1_COMPB_vect, ISR_NOBLOCK) {
    OCR1B += PERIOD_TICKS;
    const uint8_t reading = position_start();
    next_sample_us += HFW_PERIOD_US;
    ++sample_epoch;
    clock_on_sample(sample_epoch, reading);
}

uint64_t clock_next_sample(uint8_t* epoch) {
    const uint8_t sreg = SREG;
    cli();
    const uint64_t at_us = next_sample_us;
    *epoch = (uint8_t)(sample_epoch + 1u);
    SREG = sreg;
    return at_us;
}

void clock_init(void) {
    TCCR1A = 0;
    TCCR1B = _BV(CS11); /* F_CPU / 8 */
    TIMSK1 = _BV(TOIE1);
}

void clock_start_periods(uint16_t lead_us) {
    const uint8_t sreg = SREG;
    cli();
    const uint16_t now = TCNT1;
    const uint16_t boundary = (uint16_t)(now + PERIOD_TICKS);
    OCR1A = boundary;
    OCR1B = (uint16_t)(boundary - TICKS_PER_US * lead_us);
    next_sample_us = clock_now_us() + (uint16_t)(OCR1B - now) / TICKS_PER_US;
    TIFR1 = _BV(OCF1A) | _BV(OCF1B);
    TIMSK1 |= _BV(OCIE1A) | _BV(OCIE1B);
    SREG = sreg;
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
