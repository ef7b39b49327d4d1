/* The reference firmware on the ATmega328P (docs/firmware.md): the portable core
   (firmware/core/) behind this board's UART, clock, motor and position sensor.

   The loop: bytes come through the UART's ring and are COBS-decoded as they come (receive); a
   whole frame goes to the core, which sets the motor before it returns. A command or poll is
   answered with a sample from a position reading taken for it: in a session paced by the device
   (version 3, docs/protocol.md 5.8) the next period's, its sample sent as that period starts
   (paced.h); otherwise a reading started right after the force was set, so that its counts show
   that force. Between frames the loop checks the command watchdog and sleeps until the next
   interrupt (a byte, a reading, the period's start). The MCU's own watchdog resets a hung firmware
   within 15 ms, and a reset leaves the motor off. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>

#include "clock.h"
#include "hfw_cobs.h"
#include "hfw_config.h"
#include "hfw_device.h"
#include "hfw_kinematics.h"
#include "motor.h"
#include "paced.h"
#include "position.h"
#include "uart.h"

static struct hfw_device_config config = {
    .axes = 1,
    .max_version = 3,
    .paced = HFW_PACED,
    .force_limit_un = (int32_t)(HFW_FORCE_LIMIT_N * 1e6),
    .period_us = HFW_PERIOD_US,
    .default_watchdog_timeout_us = HFW_WATCHDOG_TIMEOUT_US,
    .firmware_version = HFW_FIRMWARE_VERSION,
    .serial = HFW_SERIAL,
};
static struct hfw_device device;
static struct hfw_motor_map motor_map;
static struct hfw_cobs_decoder receiver;
static uint8_t received[HFW_MAX_FRAME_SIZE];
static uint8_t pending_size; /* received[0 .. pending_size) is a whole frame to answer */
static uint8_t reply[HFW_MAX_FRAME_SIZE];
static uint8_t sample_due;     /* a command or poll awaits its sample */
static uint8_t sample_reading; /* ... from the reading that makes position_readings() this */

static void set_force(void* context, const int32_t force_un[HFW_MAX_AXES]) {
    (void)context;
    const struct hfw_duty duty = hfw_force_to_duty(&motor_map, force_un[0]);
    motor_set(duty.duty, duty.direction);
}

static uint64_t now_us(void* context) {
    (void)context;
    return clock_now_us();
}

/* A paced sample whose reading has started goes out first: the line must carry it whole
   before anything else, and it answers an earlier request. */
static void finish_paced(void) {
    if (paced_started()) paced_send(&device);
}

static void send(size_t size) {
    finish_paced();
    uart_send(hfw_cobs_encode(reply, size, uart_tx_buffer()));
}

static void send_sample(void);

static void answer(const uint8_t* frame, uint8_t size) {
    /* Every request gets its reply: one still waiting for its reading goes out now, with the
       latest (a host that does not wait for its replies). A paced front that has not started
       answers that request too: it goes now, whole. */
    if (paced_pending() && !paced_started()) {
        paced_cancel();
        sample_due = 1;
    }
    if (sample_due) send_sample();
    size_t reply_size = 0;
    const enum hfw_reply kind =
        hfw_device_receive(&device, frame, size, clock_now_us(), reply, &reply_size);
    if (kind == HFW_REPLY_FRAME) send(reply_size);
    if (kind != HFW_REPLY_SAMPLE) return;
    sample_due = 1;
    /* Paced: the main loop writes the front for the next period's reading (paced.h).
       Otherwise a reading sampled after the force was set (one under way may have sampled
       before it). */
    if (!hfw_device_paced(&device)) sample_reading = position_start();
}

/* Decodes the bytes in the receive ring until a frame is whole (it then stays in the
   decoder's buffer until answered: no byte is decoded meanwhile, they wait in the ring) or
   the line has been quiet for two byte times; while a frame is half in, it waits for the
   rest here rather than in the main loop's round. The decoder's state works on a local copy
   (9 bytes), which the compiler keeps in registers. */
static void receive(void) {
    struct hfw_cobs_decoder decoder = receiver;
    uint8_t byte = 0;
    uint8_t quiet = 0;
    while (pending_size == 0 && quiet < UART_QUIET_POLLS) {
        if (!uart_poll(&byte)) {
            if (decoder.encoded == 0) break; /* between frames: nothing to wait for */
            ++quiet;
            continue;
        }
        quiet = 0;
        if (hfw_cobs_push(&decoder, byte)) pending_size = decoder.size;
    }
    receiver = decoder;
}

/* The sample due can go now: in a paced session, its front can be written (nothing pending,
   the UART idle); otherwise its reading is in. */
static uint8_t sample_ready(void) {
    if (!sample_due) return 0;
    if (hfw_device_paced(&device)) return !paced_pending() && uart_idle();
    return position_readings() == sample_reading;
}

static void send_sample(void) {
    finish_paced(); /* its sample comes first: it has the earlier sequence number */
    uint64_t sampled_us = 0;
    uint16_t sensor_status = 0;
    int64_t counts[HFW_MAX_AXES] = {0, 0, 0};
    counts[0] = position_last(&sampled_us, &sensor_status);
    sample_due = 0;
    send(hfw_device_sample(&device, counts, sampled_us, sensor_status, reply));
}

int main(void) {
    MCUSR = 0;
    wdt_disable();
    motor_init(); /* zero force before anything else */
    hfw_motor_map_init(&motor_map, 256u, (uint32_t)(HFW_FULL_DUTY_FORCE_N * 1e6), HFW_FORCE_SIGN);
    config.counts_per_meter_bits = hfw_f64_bits(position_counts_per_meter());
    const struct hfw_board board = {.set_force = set_force, .now_us = now_us, .context = 0};
    hfw_device_init(&device, &config, board);
    hfw_cobs_init(&receiver, received);
    clock_init();
    uart_init();
    position_init();
    clock_start_periods(paced_front_lead_us());
    sei();
    wdt_enable(WDTO_15MS);
    set_sleep_mode(SLEEP_MODE_IDLE);
    for (;;) {
        wdt_reset();
        if (uart_pending() && pending_size == 0) receive();
        finish_paced(); /* even if the session just ended */
        if (pending_size != 0) {
            answer(received, pending_size);
            pending_size = 0;
        }
        if (sample_ready()) {
            if (hfw_device_paced(&device)) {
                paced_prepare(&device);
                sample_due = 0;
            } else {
                send_sample();
            }
        }
        hfw_device_check_watchdog(&device, clock_now_us());
        cli();
        if (!uart_pending() && !paced_started() && pending_size == 0 && !sample_ready()) {
            sleep_enable();
            sei();
            sleep_cpu();
            sleep_disable();
        }
        sei();
    }
}
