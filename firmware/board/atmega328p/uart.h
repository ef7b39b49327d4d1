/* USART0 at 2 Mbaud, 8N1 (UBRR0 = 0 with U2X0: exact at 16 MHz). A byte arrives every 5 us
   (80 cycles). The receive interrupt only moves each byte into a ring (about 40 cycles), so
   that no byte is lost to the USART's two-byte buffer while the main loop is busy (answering
   a frame, sending a paced sample); the main loop decodes from the ring. Frames go out from a
   buffer through the data-register-empty interrupt, or by hand (paced.c). */
#ifndef HFW_BOARD_UART_H
#define HFW_BOARD_UART_H

#include <avr/io.h>
#include <stddef.h>
#include <stdint.h>

/* The receive ring: written by the interrupt, read by the main loop only. */
#define UART_RX_RING 64u /* a power of two; a frame is at most 62 bytes on the line */
extern volatile uint8_t uart_rx_ring[UART_RX_RING];
extern volatile uint8_t uart_rx_head;
extern uint8_t uart_rx_tail;

void uart_init(void);

/* Whether a received byte is waiting in the ring (with interrupts off: to decide to sleep). */
static inline uint8_t uart_pending(void) { return uart_rx_head != uart_rx_tail; }

/* The next byte from the ring, if one has come: 1 and *byte, else 0. */
static inline uint8_t uart_poll(uint8_t* byte) {
    const uint8_t tail = uart_rx_tail;
    if (tail == uart_rx_head) return 0;
    *byte = uart_rx_ring[tail % UART_RX_RING];
    uart_rx_tail = (uint8_t)(tail + 1u);
    return 1;
}

/* Polls of the ring (about 8 cycles each) in two byte times (160 cycles): a line quiet this
   long in the middle of a frame has stopped. */
#define UART_QUIET_POLLS 20u

/* The buffer for the next frame out (HFW_COBS_MAX_ENCODED bytes), once the last one has
   gone. uart_send() sends its first `size` bytes; uart_allow() lets its first `count` go
   while the rest is still being written (an interrupt may call it), `last` when they are all.
   uart_idle(): the last frame has gone. */
uint8_t* uart_tx_buffer(void);
void uart_allow(uint8_t count, uint8_t last);
static inline void uart_send(size_t size) { uart_allow((uint8_t)size, 1); }
uint8_t uart_idle(void);

/* Sending by hand, for a frame whose end is written while its front goes out (paced.c): the
   transmit interrupt would take 63 of the 80 cycles between bytes and leave the writing too
   little. uart_tx_free(): the data register can take a byte; uart_tx_put() gives it one. The
   buffer from uart_tx_buffer() is released with uart_allow(0, 1) when done. */
static inline uint8_t uart_tx_free(void) { return (UCSR0A & _BV(UDRE0)) != 0; }
static inline void uart_tx_put(uint8_t byte) { UDR0 = byte; }

#endif
