#include "uart.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "hfw_cobs.h"

static uint8_t tx_buffer[HFW_COBS_MAX_ENCODED];
static volatile uint8_t tx_next, tx_allowed; /* sent, and allowed to go */
static volatile uint8_t tx_last = 1;         /* tx_allowed covers the whole frame */

volatile uint8_t uart_rx_ring[UART_RX_RING];
volatile uint8_t uart_rx_head;
uint8_t uart_rx_tail;

/* Nothing but the move into the ring, by hand: the compiler's version took 57 cycles of the
   80 between two bytes at 2 Mbaud (it saves registers this never touches), leaving the main
   loop too little to decode in; this one takes about 35. A ring that the main loop lets fill
   overwrites its oldest bytes, and that frame fails its CRC. */
ISR(USART_RX_vect, ISR_NAKED) {
    __asm__ volatile(
        "push r24\n\t"
        "in r24, __SREG__\n\t"
        "push r24\n\t"
        "push r30\n\t"
        "push r31\n\t"
        "lds r30, uart_rx_head\n\t"
        "andi r30, %[mask]\n\t"
        "ldi r31, 0\n\t"
        "subi r30, lo8(-(uart_rx_ring))\n\t"
        "sbci r31, hi8(-(uart_rx_ring))\n\t"
        "lds r24, %[udr]\n\t"
        "st Z, r24\n\t"
        "lds r24, uart_rx_head\n\t"
        "subi r24, 0xFF\n\t" /* + 1 */
        "sts uart_rx_head, r24\n\t"
        "pop r31\n\t"
        "pop r30\n\t"
        "pop r24\n\t"
        "out __SREG__, r24\n\t"
        "pop r24\n\t"
        "reti\n\t" ::[mask] "M"(UART_RX_RING - 1u),
        [udr] "n"(_SFR_MEM_ADDR(UDR0)));
}

ISR(USART_UDRE_vect) {
    const uint8_t next = tx_next;
    UDR0 = tx_buffer[next];
    tx_next = (uint8_t)(next + 1u);
    if (next + 1u == tx_allowed) UCSR0B &= (uint8_t)~_BV(UDRIE0); /* until more is allowed */
}

void uart_init(void) {
    UCSR0A = _BV(U2X0); /* before UBRR0: simavr takes the rate from both when UBRR0 is written */
    UBRR0 = 0;
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00); /* 8N1 */
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

uint8_t uart_idle(void) {
    const uint8_t sreg = SREG;
    cli();
    const uint8_t idle = tx_last && tx_next == tx_allowed;
    SREG = sreg;
    return idle;
}

uint8_t* uart_tx_buffer(void) {
    while (!uart_idle()) {
    } /* the last frame is still going out */
    tx_next = 0;
    tx_allowed = 0;
    tx_last = 0;
    return tx_buffer;
}

void uart_allow(uint8_t count, uint8_t last) {
    const uint8_t sreg = SREG;
    cli();
    if (count > sizeof tx_buffer) count = sizeof tx_buffer;
    tx_allowed = count;
    tx_last = last;
    if (tx_next < count) UCSR0B |= _BV(UDRIE0);
    SREG = sreg;
}
