/* The device side of the hapticd protocol (docs/protocol.md sections 3.4, 4 and 5): frame
   checks, sessions and version negotiation, commands held as a zero-order hold, the
   version-2 record of the command in effect, the command watchdog and latched faults.

   Portable C with no MCU header: the board layer (firmware/board/) feeds it whole frames
   and the time, and it drives the motor through one callback. Time is the board's 64-bit
   microsecond clock from power-up. Nothing here allocates, blocks or keeps a pointer to a
   caller's buffer. */
#ifndef HFW_DEVICE_H
#define HFW_DEVICE_H

#include <stddef.h>
#include <stdint.h>

#include "hfw_protocol.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What identity reports, fixed for the firmware's build (firmware/config/). */
struct hfw_device_config {
    uint8_t axes;           /* 1..3 */
    uint8_t max_version;    /* the newest version spoken: 1 to 3 */
    uint8_t paced;          /* in a version-3 session, answer at the next period boundary (5.8) */
    int32_t force_limit_un; /* > 0; commands beyond it are clamped */
    uint64_t counts_per_meter_bits;       /* IEEE 754 binary64 bits (hfw_f64_bits) */
    uint32_t period_us;                   /* the servo period the host must keep */
    uint32_t default_watchdog_timeout_us; /* in [2 period_us, 1 s] */
    uint32_t firmware_version;
    char serial[16]; /* 1 to 16 printable ASCII characters, padded with 0x00 */
};

/* The board's side, called by the core:
   - set_force sets the motor's force on every axis at once (uN, within the force limit; all
     zero when the device holds no force), in the same call that decided it;
   - now_us reads the board's clock: the moment a command's output was set (4.6). */
struct hfw_board {
    void (*set_force)(void* context, const int32_t force_un[HFW_MAX_AXES]);
    uint64_t (*now_us)(void* context);
    void* context;
};

struct hfw_device {
    const struct hfw_device_config* config;
    struct hfw_board board;

    /* 5.1 the session */
    uint8_t session_open;
    uint8_t version;
    uint32_t session;
    uint32_t watchdog_timeout_us;
    uint32_t sample_sequence;

    /* 5.2 the commands: the last one accepted and what is held */
    uint8_t command_seen; /* arms the watchdog (5.4) */
    uint32_t command_sequence;
    uint64_t command_arrival_us;
    int32_t force_un[HFW_MAX_AXES]; /* the force being output */
    uint8_t force_active;
    uint8_t force_clamped;
    uint16_t command_status; /* command_late, command_gap for the sample answering it */

    /* 4.6 version 2: the last two commands that took effect, and when; a sample latched
       before the last one took effect names the one before */
    uint8_t applied_known; /* how many of the two are known: 0..2 */
    uint32_t applied_sequence;
    uint64_t applied_us;
    uint32_t previous_sequence;
    uint64_t previous_us;

    /* 5.5 faults: latched bits, and the causes still present (cleared only when gone) */
    uint16_t latched_faults;
    uint16_t fault_causes;

    /* counters, for the board's diagnostics (they wrap) */
    uint16_t dropped_frames;
    uint16_t errors_sent;
    uint16_t watchdog_trips;
};

/* Starts with no session and zero force (power-up, 5.1). */
void hfw_device_init(struct hfw_device* d, const struct hfw_device_config* config,
                     struct hfw_board board);

/* What a request needs from the board after hfw_device_receive(). */
enum hfw_reply {
    HFW_REPLY_NONE = 0,  /* dropped (3.4 checks 1-5): nothing to send */
    HFW_REPLY_FRAME = 1, /* the reply frame is in `out` */
    HFW_REPLY_SAMPLE = 2 /* latch the encoders, then hfw_device_sample() writes the reply */
};

/* One received frame (COBS already removed) whose last byte arrived at `now_us`. Applies
   what it asks (the force, through set_force, before returning) and writes any reply other than a
   sample to `out` (HFW_MAX_FRAME_SIZE bytes), its size in *out_size. */
enum hfw_reply hfw_device_receive(struct hfw_device* d, const uint8_t* frame, size_t size,
                                  uint64_t now_us, uint8_t* out, size_t* out_size);

/* The sample answering the last command or poll, from counts sampled at `time_us` (in
   version 1, after the force took effect; in versions 2 and 3 the sample names the command
   that was in effect then); `sensor_status` holds HFW_STATUS_ENCODER_STALE/JUMP as the board
   saw them. Writes the frame to `out` and returns its size. */
size_t hfw_device_sample(struct hfw_device* d, const int64_t counts[HFW_MAX_AXES], uint64_t time_us,
                         uint16_t sensor_status, uint8_t* out);

/* The same sample in two parts, so that a board can send the front of it while the sensor
   is still sampling (5.8): hfw_device_sample_begin() writes the frame up to the counts, for
   counts sampled at time_us, and returns the CRC's state over it; it changes nothing, and may
   be called again (a command that came meanwhile changes what it writes).
   hfw_device_sample_end() writes the counts and the CRC, commits the sample (its sequence
   number) and returns the frame's size. hfw_device_sample() is the two together. */
uint32_t hfw_device_sample_begin(const struct hfw_device* d, uint64_t time_us,
                                 uint16_t sensor_status, uint8_t* out);
size_t hfw_device_sample_end(struct hfw_device* d, uint32_t crc_state,
                             const int64_t counts[HFW_MAX_AXES], uint8_t* out);
/* hfw_device_sample_end() in steps, for a board that sends the frame while it finishes it:
   hfw_device_sample_counts() writes the counts at HFW_SAMPLE_COUNTS_OFFSET; the caller runs
   the CRC's state over those bytes (hfw_crc32c_update); hfw_device_sample_close() writes the
   CRC, commits the sample and returns the frame's size. */
void hfw_device_sample_counts(const struct hfw_device* d, const int64_t counts[HFW_MAX_AXES],
                              uint8_t* out);
size_t hfw_device_sample_close(struct hfw_device* d, uint32_t crc_state, uint8_t* out);
/* Where the counts start in a sample frame: the size of what hfw_device_sample_begin()
   writes. */
#define HFW_SAMPLE_COUNTS_OFFSET (HFW_HEADER_SIZE + 24u)

/* 5.8: whether this session is paced by the device (version 3 and config->paced): every
   command and poll is then answered at the next period boundary, with counts sampled for it. */
int hfw_device_paced(const struct hfw_device* d);

/* 5.4: call at least once a period (and whenever convenient). Zeroes the force and latches
   the watchdog fault at the first call at or after the timeout. Returns 1 when it tripped. */
int hfw_device_check_watchdog(struct hfw_device* d, uint64_t now_us);

/* 5.5: the board's own faults (HFW_FAULT_*): `present` are the causes now (they latch and
   zero the force at once); a latched fault clears only when its cause is gone. */
void hfw_device_set_fault_causes(struct hfw_device* d, uint16_t present);

/* The IEEE 754 binary64 bits of a float (exact: every float is a double), for
   counts_per_meter on compilers whose double is 32 bits wide (avr-gcc). */
uint64_t hfw_f64_bits(float value);

#ifdef __cplusplus
}
#endif

#endif
