/* USART0 at 2 Mbaud, 8N1 (UBRR0 = 0 with U2X0: exact at 16 MHz): bytes in through the
   receive interrupt into a ring, one frame out at a time through the data-register-empty
   interrupt. */
#ifndef HFW_BOARD_UART_H
#define HFW_BOARD_UART_H

#include <stddef.h>
#include <stdint.h>

void uart_init(void);

/* The next received byte: 1 and *byte, or 0 when none is waiting. */
uint8_t uart_read(uint8_t* byte);

/* Whether a received byte is waiting (call with interrupts off to decide to sleep). */
uint8_t uart_pending(void);

/* Bytes lost because the ring was full (the main loop fell behind). */
uint16_t uart_overruns(void);

/* Queues `size` bytes (<= 64) for sending, after any still going out. */
void uart_write(const uint8_t* bytes, size_t size);

#endif
