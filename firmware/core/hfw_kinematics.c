#include "hfw_kinematics.h"

#define DUTY_FRACTION_BITS 22u

void hfw_motor_map_init(struct hfw_motor_map* map, uint16_t duty_top, uint32_t full_duty_un,
                        int8_t force_sign) {
    map->duty_top = duty_top;
    map->full_duty_un = full_duty_un;
    uint8_t shift = 0;
    while ((full_duty_un >> shift) >= 0x10000u) ++shift;
    map->shift = shift;
    /* duty_top * 2^(22 + shift) / full_duty_un, rounded: at most duty_top * 2^22 / 2^15 */
    const uint64_t scaled = ((uint64_t)duty_top << (DUTY_FRACTION_BITS + shift));
    map->multiplier = (uint32_t)((scaled + full_duty_un / 2u) / full_duty_un);
    map->force_sign = force_sign < 0 ? -1 : 1;
}

struct hfw_duty hfw_force_to_duty(const struct hfw_motor_map* map, int32_t force_un) {
    struct hfw_duty out;
    const uint8_t negative = force_un < 0;
    out.direction = negative ^ (map->force_sign < 0);
    /* |force_un| without negating INT32_MIN */
    const uint32_t magnitude_un = negative ? (uint32_t)(-(force_un + 1)) + 1u : (uint32_t)force_un;
    if (magnitude_un >= map->full_duty_un) {
        out.duty = map->duty_top;
        return out;
    }
    const uint32_t scaled_un = magnitude_un >> map->shift; /* < 2^16: shift says so */
    /* Both factors fit 16 bits when duty_top <= 256 (the multiplier is then below 2^15): a
       16 x 16 -> 32 product, a third of a 32 x 32 one on the AVR, and the same number. */
    const uint32_t product = map->multiplier <= 0xFFFFu
                                 ? (uint32_t)(uint16_t)scaled_un * (uint16_t)map->multiplier
                                 : scaled_un * map->multiplier;
    out.duty = (uint16_t)((product + (1ul << (DUTY_FRACTION_BITS - 1u))) >> DUTY_FRACTION_BITS);
    if (out.duty > map->duty_top) out.duty = map->duty_top;
    return out;
}

void hfw_mr_sensor_init(struct hfw_mr_sensor* s, int16_t counts_per_flip, int16_t flip_threshold) {
    s->counts_per_flip = counts_per_flip;
    s->flip_threshold = flip_threshold;
    s->last_raw = -1;
    s->flips = 0;
    s->offset = 0;
}

int32_t hfw_mr_sensor_update(struct hfw_mr_sensor* s, int16_t raw) {
    if (s->last_raw >= 0) {
        const int16_t step = (int16_t)(raw - s->last_raw);
        if (step < -s->flip_threshold) { /* climbed past the top: a half turn up */
            ++s->flips;
            s->offset += s->counts_per_flip;
        }
        if (step > s->flip_threshold) {
            --s->flips;
            s->offset -= s->counts_per_flip;
        }
    }
    s->last_raw = raw;
    return raw + s->offset;
}

int8_t hfw_quadrature_step(uint8_t from, uint8_t to) {
    /* Gray code A B: 00 -> 01 -> 11 -> 10 -> 00 is +1 */
    static const int8_t step[16] = {0,
                                    +1,
                                    -1,
                                    HFW_QUADRATURE_ILLEGAL, /* from 00 */
                                    -1,
                                    0,
                                    HFW_QUADRATURE_ILLEGAL,
                                    +1, /* from 01 */
                                    +1,
                                    HFW_QUADRATURE_ILLEGAL,
                                    0,
                                    -1, /* from 10 */
                                    HFW_QUADRATURE_ILLEGAL,
                                    -1,
                                    +1,
                                    0}; /* from 11 */
    return step[((from & 3u) << 2) | (to & 3u)];
}
