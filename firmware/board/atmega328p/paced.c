#include "paced.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "clock.h"
#include "hfw_cobs.h"
#include "hfw_crc32c.h"
#include "position.h"
#include "uart.h"

static uint8_t frame[HFW_MAX_FRAME_SIZE];
static struct hfw_cobs_encoder encoder;
static uint32_t crc_state;
static volatile uint8_t written;  /* a front is in the UART's buffer */
static volatile uint8_t started;  /* its period has started: it is going out */
static volatile uint8_t sampling; /* its reading has started */
static volatile uint8_t period;   /* the period it is for */
static volatile uint8_t reading;  /* position_readings() once that reading is in */

/* On the line at 2 Mbaud, 8N1: 5 us a byte. The counts of a sample are its 33rd byte on the
   line (the 32 before them and COBS's one); finishing the frame once they are in takes about
   60 us. */
#define BYTE_US 5u

uint16_t paced_front_lead_us(void) {
    return (uint16_t)((HFW_SAMPLE_COUNTS_OFFSET + 1u) * BYTE_US - position_conversion_us());
}

void clock_on_period(uint8_t started_period) {
    if (written && !started && started_period == period) started = 1;
}

void clock_on_sample(uint8_t sample_period, uint8_t sample_reading) {
    if (!started || sampling || sample_period != period) return;
    reading = sample_reading;
    sampling = 1;
}

void paced_prepare(const struct hfw_device* d) {
    for (;;) {
        written = 0;
        uint8_t next_period = 0;
        const uint64_t start_us = clock_next_period(&next_period);
        crc_state = hfw_device_sample_begin(d, start_us + position_sample_delay_us(), 0, frame);
        hfw_cobs_start(&encoder, uart_tx_buffer());
        hfw_cobs_put(&encoder, frame, HFW_SAMPLE_COUNTS_OFFSET);
        cli();
        uint8_t now_period = 0;
        (void)clock_next_period(&now_period);
        const uint8_t in_time = now_period == next_period; /* that period has not started */
        if (in_time) {
            period = next_period;
            started = 0;
            sampling = 0;
            written = 1;
        }
        sei();
        if (in_time) return;
        uart_allow(0, 1); /* that period started while the front was written: release the
                             buffer, and write it for the next one */
    }
}

uint8_t paced_pending(void) { return written; }
uint8_t paced_started(void) { return started; }

void paced_cancel(void) {
    cli();
    const uint8_t drop = written && !started;
    if (drop) written = 0;
    sei();
    if (drop) uart_allow(0, 1); /* nothing of it went out: the buffer is free again */
}

/* The bytes of the UART's buffer sent so far, by hand. */
static uint8_t sent;

/* The UART's two bytes (its data register and its shift register) filled with what is final.
   Called at least every 140 cycles, the line never idles while there is something to send. */
static inline void feed(void) {
    while (uart_tx_free() && sent < hfw_cobs_final(&encoder)) uart_tx_put(encoder.out[sent++]);
}

/* Sends until the period's reading has started and is in. */
static void send_until_reading(void) {
    while (!sampling || position_readings() != reading) feed();
}

/* Runs `size` bytes of the frame through the CRC (or the COBS encoder) four at a time, a feed
   between each: four bytes are about 140 cycles of either. */
static void crc_bytes(uint8_t from, uint8_t size) {
    for (uint8_t i = 0; i < size; i = (uint8_t)(i + 4u)) {
        const uint8_t left = (uint8_t)(size - i);
        const uint8_t n = left < 4u ? left : 4u;
        crc_state = hfw_crc32c_update(crc_state, frame + from + i, n);
        feed();
    }
}

static void encode_bytes(uint8_t from, uint8_t size) {
    for (uint8_t i = 0; i < size; i = (uint8_t)(i + 4u)) {
        const uint8_t left = (uint8_t)(size - i);
        const uint8_t n = left < 4u ? left : 4u;
        hfw_cobs_put(&encoder, frame + from + i, n);
        feed();
    }
}

void paced_send(struct hfw_device* d) {
    sent = 0;
    send_until_reading();
    uint64_t sampled_us =
        0; /* the front said when: the start the clock scheduled, plus the delay */
    uint16_t status = 0;
    int64_t counts[HFW_MAX_AXES] = {0, 0, 0};
    counts[0] = position_last(&sampled_us, &status);
    feed();
    hfw_device_sample_counts(d, counts, frame);
    feed();
    /* The counts onto the line first (as far as COBS lets them: up to their last zero), and
       their CRC while they go. */
    const uint8_t counts_size = (uint8_t)(8u * d->config->axes);
    encode_bytes(HFW_SAMPLE_COUNTS_OFFSET, counts_size);
    crc_bytes(HFW_SAMPLE_COUNTS_OFFSET, counts_size);
    const uint8_t size = (uint8_t)hfw_device_sample_close(d, crc_state, frame);
    feed();
    const uint8_t crc_at = (uint8_t)(HFW_SAMPLE_COUNTS_OFFSET + counts_size);
    encode_bytes(crc_at, (uint8_t)(size - crc_at));
    const uint8_t total = (uint8_t)hfw_cobs_finish(&encoder);
    while (sent < total) feed();
    uart_allow(0, 1);
    cli();
    written = 0;
    started = 0;
    sampling = 0;
    sei();
}
