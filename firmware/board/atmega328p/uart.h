/* USART0 at 2 Mbaud, 8N1 (UBRR0 = 0 with U2X0: exact at 16 MHz). A byte arrives every
   5 us (80 cycles): too often for an interrupt per byte and the decoding behind it, so the
   receive interrupt only wakes the main loop, which then reads the bytes itself as they come
   (uart_receive). Frames go out from a buffer through the data-register-empty interrupt. */
#ifndef HFW_BOARD_UART_H
#define HFW_BOARD_UART_H

#include <avr/io.h>
#include <stddef.h>
#include <stdint.h>

void uart_init(void);

/* Whether a received byte is waiting (call with interrupts off to decide to sleep). */
uint8_t uart_pending(void);

/* The next byte, if one has come: 1 and *byte, else 0. Inline: the main loop reads each
   byte itself, with nothing but its decoding between two reads. */
static inline uint8_t uart_poll(uint8_t* byte) {
    if (!(UCSR0A & _BV(RXC0))) return 0;
    *byte = UDR0;
    return 1;
}

/* Polls of UCSR0A (about 8 cycles each) in two byte times (160 cycles): a line quiet this
   long between bytes has finished its frame. */
#define UART_QUIET_POLLS 20u

/* The main loop has read what came: the next byte wakes it again. */
void uart_receive_done(void);

/* The buffer for the next frame out (HFW_COBS_MAX_ENCODED bytes), once the last one has
   gone. uart_send() sends its first `size` bytes; uart_allow() lets its first `count` go
   while the rest is still being written (an interrupt may call it), `last` when they are all.
   uart_idle(): the last frame has gone. */
uint8_t* uart_tx_buffer(void);
void uart_allow(uint8_t count, uint8_t last);
static inline void uart_send(size_t size) { uart_allow((uint8_t)size, 1); }
uint8_t uart_idle(void);

#endif
