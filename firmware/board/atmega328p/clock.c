#include "clock.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "hfw_config.h"

#if F_CPU != 16000000UL
#error "clock.c counts 0.5 us ticks: F_CPU must be 16 MHz"
#endif

/* The microseconds at the last overflow: 65536 ticks are 32,768 us. Kept whole so that
   reading the clock costs an add, not a 64-bit shift (a library call on the AVR). */
static volatile uint64_t overflow_us;

ISR(TIMER1_OVF_vect) { overflow_us += 32768u; }

/* Compare match A every period: it only wakes the main loop, which then checks the command
   watchdog (docs/protocol.md 5.4: at the latest at the first period boundary after the
   timeout). */
ISR(TIMER1_COMPA_vect) { OCR1A += 2u * HFW_PERIOD_US; }

void clock_init(void) {
    TCCR1A = 0;
    TCCR1B = _BV(CS11); /* F_CPU / 8 */
    OCR1A = 2u * HFW_PERIOD_US;
    TIMSK1 = _BV(TOIE1) | _BV(OCIE1A);
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
