#include "clock.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#if F_CPU != 16000000UL
#error "clock.c counts 0.5 us ticks: F_CPU must be 16 MHz"
#endif

static volatile uint32_t overflows; /* 65536 ticks = 32,768 us each: 4.5 years */

ISR(TIMER1_OVF_vect) { ++overflows; }

void clock_init(void) {
    TCCR1A = 0;
    TCCR1B = _BV(CS11); /* F_CPU / 8 */
    TIMSK1 = _BV(TOIE1);
}

uint64_t clock_now_us(void) {
    const uint8_t sreg = SREG;
    cli();
    uint16_t ticks = TCNT1;
    uint32_t wraps = overflows;
    if ((TIFR1 & _BV(TOV1)) && ticks < 0x8000u) ++wraps; /* wrapped, ISR not yet run */
    SREG = sreg;
    return ((uint64_t)wraps << 15) | (ticks >> 1);
}
