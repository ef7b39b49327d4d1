/* Between the wire's units and the board's: force on the handle to motor duty, and the
   position sensors' readings to counts (docs/firmware.md, "Kinematics"). Integer only: the
   ATmega328P has no FPU and 32-bit floats would cost more than the whole exchange's CRC. */
#ifndef HFW_KINEMATICS_H
#define HFW_KINEMATICS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- force to duty ---- */

/* A linear motor map: the force on the handle is proportional to the PWM duty, with the
   direction on a pin. full_duty_un = force on the handle at 100 % duty
   (motor torque at full duty * sector radius / (handle radius * capstan radius)). */
struct hfw_motor_map {
    uint16_t duty_top;     /* the PWM's count at 100 % (256 for Timer0 with its off state) */
    uint32_t full_duty_un; /* the force at 100 % */
    /* duty = ((|force| >> shift) * multiplier) >> 22 in 32 bits: shift keeps the force at
       full duty below 2^16, so the product stays below 2^30 (a 64-bit product costs about
       300 cycles on the AVR, this one 60) */
    uint8_t shift;
    uint32_t multiplier;
    int8_t force_sign; /* +1, or -1 when a positive duty with direction 1 pushes the handle
                          towards -x */
};

struct hfw_duty {
    uint16_t duty;     /* 0..duty_top */
    uint8_t direction; /* 1: the direction pin high */
};

/* full_duty_un > 0. */
void hfw_motor_map_init(struct hfw_motor_map* map, uint16_t duty_top, uint32_t full_duty_un,
                        int8_t force_sign);

/* The duty for force_un (rounded to the nearest step, at most duty_top). */
struct hfw_duty hfw_force_to_duty(const struct hfw_motor_map* map, int32_t force_un);

/* ---- the magnetoresistive angle sensor (Hapkit): a sawtooth over each half turn ---- */

/* The sensor's output climbs over a half turn of the motor shaft and falls back by about
   counts_per_flip at the end of it. A step larger than flip_threshold between two readings
   is a flip (the course code's 700 of 1023); readings must come often enough that the shaft
   turns less than flip_threshold between two. */
struct hfw_mr_sensor {
    int16_t counts_per_flip; /* the sawtooth's height in ADC counts */
    int16_t flip_threshold;
    int16_t last_raw; /* -1 before the first reading */
    int32_t flips;
    int32_t offset; /* flips * counts_per_flip, kept so that a reading costs no multiply */
};

void hfw_mr_sensor_init(struct hfw_mr_sensor* s, int16_t counts_per_flip, int16_t flip_threshold);

/* One ADC reading (0..1023); returns the unwrapped position in ADC counts:
   raw + flips * counts_per_flip. */
int32_t hfw_mr_sensor_update(struct hfw_mr_sensor* s, int16_t raw);

/* ---- a quadrature encoder: x4 decoding ---- */

#define HFW_QUADRATURE_ILLEGAL 2

/* The step from channel state `from` to `to` (bit 1 = A, bit 0 = B): -1, 0, +1, or
   HFW_QUADRATURE_ILLEGAL when both channels changed at once (an edge was missed). */
int8_t hfw_quadrature_step(uint8_t from, uint8_t to);

#ifdef __cplusplus
}
#endif

#endif
