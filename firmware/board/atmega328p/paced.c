#include "paced.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "clock.h"
#include "hfw_cobs.h"
#include "position.h"
#include "uart.h"

static uint8_t frame[HFW_MAX_FRAME_SIZE];
static struct hfw_cobs_encoder encoder;
static uint32_t crc_state;
static volatile uint8_t written; /* a front is in the UART's buffer */
static volatile uint8_t started; /* the clock has let it go */
static volatile uint8_t epoch;   /* the reading it is for */
static volatile uint8_t reading; /* position_readings() once that reading is in */

void clock_on_sample(uint8_t sample_epoch, uint8_t sample_reading) {
    if (!written || started || sample_epoch != epoch) return;
    started = 1;
    reading = sample_reading;
    uart_allow(hfw_cobs_final(&encoder), 0);
}

void paced_prepare(const struct hfw_device* d) {
    for (;;) {
        written = 0;
        uint8_t next_epoch = 0;
        const uint64_t start_us = clock_next_sample(&next_epoch);
        crc_state = hfw_device_sample_begin(d, start_us + position_sample_delay_us(), 0, frame);
        hfw_cobs_start(&encoder, uart_tx_buffer());
        hfw_cobs_put(&encoder, frame, HFW_SAMPLE_COUNTS_OFFSET);
        cli();
        uint8_t now_epoch = 0;
        (void)clock_next_sample(&now_epoch);
        const uint8_t in_time = now_epoch == next_epoch; /* that reading has not started */
        if (in_time) {
            epoch = next_epoch;
            started = 0;
            written = 1;
        }
        sei();
        if (in_time) return;
        uart_allow(0, 1); /* that reading started while the front was written: release the
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

uint8_t paced_ready_to_finish(void) { return started && position_readings() == reading; }

void paced_finish(struct hfw_device* d) {
    uint64_t sampled_us = 0;
    uint16_t status = 0;
    int64_t counts[HFW_MAX_AXES] = {0, 0, 0};
    counts[0] = position_last(&sampled_us, &status);
    (void)sampled_us; /* the front said when: the start the clock scheduled, plus the delay */
    const size_t size = hfw_device_sample_end(d, crc_state, counts, frame);
    hfw_cobs_put(&encoder, frame + HFW_SAMPLE_COUNTS_OFFSET, size - HFW_SAMPLE_COUNTS_OFFSET);
    uart_allow((uint8_t)hfw_cobs_finish(&encoder), 1);
    cli();
    written = 0;
    started = 0;
    sei();
}
