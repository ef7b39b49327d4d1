#include "uart.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <string.h>

#define RX_RING 128u /* a power of two: two whole frames on the line */
#define TX_BUFFER 64u

static volatile uint8_t rx_ring[RX_RING];
static volatile uint8_t rx_head, rx_tail;
static volatile uint16_t rx_overruns;

static uint8_t tx_buffer[TX_BUFFER];
static volatile uint8_t tx_next, tx_size;

ISR(USART_RX_vect) {
    const uint8_t byte = UDR0;
    const uint8_t head = rx_head;
    if ((uint8_t)(head - rx_tail) == RX_RING) {
        ++rx_overruns;
        return;
    }
    rx_ring[head % RX_RING] = byte;
    rx_head = head + 1u;
}

ISR(USART_UDRE_vect) {
    UDR0 = tx_buffer[tx_next++];
    if (tx_next == tx_size) UCSR0B &= (uint8_t)~_BV(UDRIE0);
}

void uart_init(void) {
    UCSR0A = _BV(U2X0); /* before UBRR0: simavr takes the rate from both when UBRR0 is written */
    UBRR0 = 0;
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00); /* 8N1 */
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
}

uint8_t uart_read(uint8_t* byte) {
    const uint8_t tail = rx_tail;
    if (tail == rx_head) return 0;
    *byte = rx_ring[tail % RX_RING];
    rx_tail = tail + 1u;
    return 1;
}

uint16_t uart_overruns(void) {
    const uint8_t sreg = SREG;
    cli();
    const uint16_t n = rx_overruns;
    SREG = sreg;
    return n;
}

void uart_write(const uint8_t* bytes, size_t size) {
    if (size == 0 || size > TX_BUFFER) return;
    while (UCSR0B & _BV(UDRIE0)) {
    } /* the last frame is still going out */
    memcpy(tx_buffer, bytes, size);
    tx_next = 0;
    tx_size = (uint8_t)size;
    UCSR0B |= _BV(UDRIE0);
}

uint8_t uart_pending(void) { return rx_tail != rx_head; }
