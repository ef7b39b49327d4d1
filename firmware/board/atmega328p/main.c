/* The reference firmware on the ATmega328P (docs/firmware.md): the portable core
   (firmware/core/) behind this board's UART, clock, motor and position sensor.

   The loop: bytes from the UART ring are COBS-decoded as they come; a whole frame goes to
   the core, which sets the motor before it returns; a command or poll is answered with the
   counts latched right after. Between frames the loop checks the command watchdog and sleeps
   until the next interrupt (a byte, an ADC conversion, the clock's tick every period). The MCU's
   own watchdog resets a hung firmware within 15 ms, and a reset leaves the motor off. */
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
#include "position.h"
#include "uart.h"

static struct hfw_device_config config = {
    .axes = 1,
    .max_version = 2,
    .force_limit_un = (int32_t)(HFW_FORCE_LIMIT_N * 1e6),
    .period_us = HFW_PERIOD_US,
    .default_watchdog_timeout_us = HFW_WATCHDOG_TIMEOUT_US,
    .firmware_version = HFW_FIRMWARE_VERSION,
    .serial = HFW_SERIAL,
};
static struct hfw_device device;
static struct hfw_motor_map motor_map;
static struct hfw_cobs_decoder receiver;
static uint8_t reply[HFW_MAX_FRAME_SIZE];
static uint8_t line[HFW_COBS_MAX_ENCODED];

static void set_force(void* context, const int32_t force_un[HFW_MAX_AXES]) {
    (void)context;
    const struct hfw_duty duty = hfw_force_to_duty(&motor_map, force_un[0]);
    motor_set(duty.duty, duty.direction);
}

static uint64_t now_us(void* context) {
    (void)context;
    return clock_now_us();
}

static void answer(const uint8_t* frame, uint8_t size) {
    size_t reply_size = 0;
    const enum hfw_reply kind =
        hfw_device_receive(&device, frame, size, clock_now_us(), reply, &reply_size);
    if (kind == HFW_REPLY_NONE) return;
    if (kind == HFW_REPLY_SAMPLE) {
        const uint64_t time_us = clock_now_us();
        uint16_t sensor_status = 0;
        int64_t counts[HFW_MAX_AXES] = {0, 0, 0};
        counts[0] = position_latch(time_us, &sensor_status);
        reply_size = hfw_device_sample(&device, counts, time_us, sensor_status, reply);
    }
    uart_write(line, hfw_cobs_encode(reply, reply_size, line));
}

int main(void) {
    MCUSR = 0;
    wdt_disable();
    motor_init(); /* zero force before anything else */
    hfw_motor_map_init(&motor_map, 256u, (uint32_t)(HFW_FULL_DUTY_FORCE_N * 1e6), HFW_FORCE_SIGN);
    config.counts_per_meter_bits = hfw_f64_bits(position_counts_per_meter());
    const struct hfw_board board = {.set_force = set_force, .now_us = now_us, .context = 0};
    hfw_device_init(&device, &config, board);
    hfw_cobs_reset(&receiver);
    clock_init();
    uart_init();
    position_init();
    sei();
    wdt_enable(WDTO_15MS);
    set_sleep_mode(SLEEP_MODE_IDLE);
    for (;;) {
        wdt_reset();
        uint8_t byte;
        while (uart_read(&byte)) {
            if (hfw_cobs_push(&receiver, byte)) answer(receiver.frame, receiver.size);
        }
        hfw_device_check_watchdog(&device, clock_now_us());
        cli();
        if (!uart_pending()) {
            sleep_enable();
            sei();
            sleep_cpu();
            sleep_disable();
        }
        sei();
    }
}
