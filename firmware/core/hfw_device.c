#include "hfw_device.h"

#include <string.h>

#include "hfw_crc32c.h"
#include "hfw_wire.h"

static const int32_t kZeroForce[HFW_MAX_AXES] = {0, 0, 0};

void hfw_device_init(struct hfw_device* d, const struct hfw_device_config* config,
                     struct hfw_board board) {
    memset(d, 0, sizeof *d);
    d->config = config;
    d->board = board;
    d->watchdog_timeout_us = config->default_watchdog_timeout_us;
    board.set_force(board.context, kZeroForce);
}

/* ---- output: 5.2 (ZOH), 5.4, 5.5 ---- */

static void output(struct hfw_device* d, const int32_t force_un[HFW_MAX_AXES], uint8_t active) {
    memcpy(d->force_un, force_un, sizeof d->force_un);
    d->force_active = active;
    d->board.set_force(d->board.context, d->force_un);
}

static void zero_force(struct hfw_device* d) { output(d, kZeroForce, 0); }

static void close_session(struct hfw_device* d) {
    zero_force(d);
    d->session_open = 0;
    d->command_seen = 0;
    d->applied_known = 0;
}

/* ---- replies ---- */

/* Header and CRC around a payload already written at out + 8; returns the frame's size. */
static size_t finish(uint8_t version, uint8_t type, uint8_t payload_size, uint32_t session,
                     uint8_t* out) {
    out[0] = HFW_MAGIC;
    out[1] = version;
    out[2] = type;
    out[3] = payload_size;
    hfw_store_u32(out + 4, session);
    const size_t crc_at = HFW_HEADER_SIZE + payload_size;
    hfw_store_u32(out + crc_at, hfw_crc32c(out, crc_at));
    return crc_at + HFW_CRC_SIZE;
}

static uint32_t version_range(const struct hfw_device* d) {
    return HFW_MIN_VERSION | ((uint32_t)d->config->max_version << 8);
}

/* 4.10: nothing of the request was applied. */
static size_t error_reply(struct hfw_device* d, uint32_t session, uint8_t request_type,
                          uint8_t code, uint32_t detail, uint8_t* out) {
    out[8] = code;
    out[9] = request_type;
    hfw_store_u16(out + 10, 0);
    hfw_store_u32(out + 12, detail);
    ++d->errors_sent;
    return finish(HFW_FROZEN_VERSION, HFW_ERROR, HFW_ERROR_PAYLOAD, session, out);
}

/* ---- 3.4 the checks of a frame, in order ---- */

static int is_host_to_device(uint8_t type) { return type >= HFW_HELLO && type <= HFW_BYE; }

static int is_message_type(uint8_t type) {
    return is_host_to_device(type) || type == HFW_IDENTITY || type == HFW_CONFIGURE_ACK ||
           type == HFW_SAMPLE || type == HFW_BYE_ACK || type == HFW_ERROR;
}

/* Checks 1-5; 0 when the frame is to be dropped silently. */
static int frame_intact(const uint8_t* frame, size_t size) {
    if (size < HFW_MIN_FRAME_SIZE || frame[0] != HFW_MAGIC) return 0;
    const uint8_t payload_size = frame[3];
    if (payload_size > HFW_MAX_PAYLOAD_SIZE || size != HFW_MIN_FRAME_SIZE + payload_size) {
        return 0;
    }
    const size_t crc_at = HFW_HEADER_SIZE + payload_size;
    return hfw_crc32c(frame, crc_at) == hfw_load_u32(frame + crc_at);
}

/* Checks 8-9 for the host-to-device types: 0, or the error code. */
static uint8_t payload_error(uint8_t type, const uint8_t* payload, uint8_t payload_size) {
    switch (type) {
        case HFW_HELLO:
            if (payload_size != HFW_HELLO_PAYLOAD) return HFW_ERROR_BAD_LENGTH;
            if (hfw_load_u16(payload + 2) != 0 || payload[0] == 0 || payload[1] < payload[0]) {
                return HFW_ERROR_BAD_FIELD;
            }
            return 0;
        case HFW_CONFIGURE:
            if (payload_size != HFW_CONFIGURE_PAYLOAD) return HFW_ERROR_BAD_LENGTH;
            return hfw_load_u32(payload) == 0 ? HFW_ERROR_BAD_FIELD : 0;
        case HFW_COMMAND: {
            if (payload_size != HFW_COMMAND_PAYLOAD(1) && payload_size != HFW_COMMAND_PAYLOAD(2) &&
                payload_size != HFW_COMMAND_PAYLOAD(3)) {
                return HFW_ERROR_BAD_LENGTH;
            }
            const uint8_t flags = payload[4], axes = payload[5];
            if (hfw_load_u16(payload + 6) != 0 || axes < 1 || axes > HFW_MAX_AXES ||
                payload_size != HFW_COMMAND_PAYLOAD(axes) ||
                (flags & ~(HFW_COMMAND_ENABLE | HFW_COMMAND_CLEAR_FAULTS)) != 0) {
                return HFW_ERROR_BAD_FIELD;
            }
            return 0;
        }
        default: /* poll, bye */
            return payload_size == 0 ? 0 : HFW_ERROR_BAD_LENGTH;
    }
}

/* ---- 5.1 hello ---- */

static enum hfw_reply on_hello(struct hfw_device* d, uint32_t session, const uint8_t* payload,
                               uint8_t* out, size_t* out_size) {
    close_session(d); /* any hello ends the current session first, force zero */
    const uint8_t low = payload[0] > HFW_MIN_VERSION ? payload[0] : HFW_MIN_VERSION;
    const uint8_t high = payload[1] < d->config->max_version ? payload[1] : d->config->max_version;
    if (high < low) {
        *out_size = error_reply(d, session, HFW_HELLO, HFW_ERROR_UNSUPPORTED_VERSION,
                                version_range(d), out);
        return HFW_REPLY_FRAME;
    }
    d->session_open = 1;
    d->session = session;
    d->version = high;
    d->watchdog_timeout_us = d->config->default_watchdog_timeout_us;
    d->sample_sequence = 0;
    d->command_sequence = 0;
    d->force_clamped = 0;
    d->command_status = 0;
    d->latched_faults &= (uint16_t)~HFW_FAULT_WATCHDOG; /* the host that let it trip is gone */
    const struct hfw_device_config* c = d->config;
    uint8_t* p = out + HFW_HEADER_SIZE;
    p[0] = c->axes;
    p[1] = hfw_device_paced(d) ? HFW_IDENTITY_PACED : 0u; /* reserved before version 3 */
    hfw_store_u16(p + 2, 0);
    hfw_store_u32(p + 4, (uint32_t)c->force_limit_un);
    hfw_store_u64(p + 8, c->counts_per_meter_bits);
    hfw_store_u32(p + 16, c->period_us);
    hfw_store_u32(p + 20, d->watchdog_timeout_us);
    hfw_store_u32(p + 24, c->firmware_version);
    memcpy(p + 28, c->serial, sizeof c->serial);
    *out_size = finish(d->version, HFW_IDENTITY, HFW_IDENTITY_PAYLOAD, session, out);
    return HFW_REPLY_FRAME;
}

/* ---- 5.4 configure ---- */

static size_t on_configure(struct hfw_device* d, const uint8_t* payload, uint8_t* out) {
    const uint32_t least_us = 2u * d->config->period_us;
    const uint32_t timeout_us = hfw_load_u32(payload);
    if (timeout_us < least_us || timeout_us > HFW_MAX_WATCHDOG_TIMEOUT_US) {
        const uint32_t nearest = timeout_us < least_us ? least_us : HFW_MAX_WATCHDOG_TIMEOUT_US;
        return error_reply(d, d->session, HFW_CONFIGURE, HFW_ERROR_OUT_OF_RANGE, nearest, out);
    }
    d->watchdog_timeout_us = timeout_us;
    hfw_store_u32(out + HFW_HEADER_SIZE, timeout_us);
    return finish(d->version, HFW_CONFIGURE_ACK, HFW_CONFIGURE_PAYLOAD, d->session, out);
}

/* ---- 5.2 command ---- */

static void on_command(struct hfw_device* d, const uint8_t* payload, uint64_t now_us) {
    /* The force first, the bookkeeping after: every cycle before output() is loop delay. */
    const uint8_t flags = payload[4];
    const int enable = (flags & HFW_COMMAND_ENABLE) != 0;
    if ((flags & HFW_COMMAND_CLEAR_FAULTS) != 0 && !enable) {
        d->latched_faults = d->fault_causes; /* 5.5: those whose cause has gone */
    }
    int32_t force_un[HFW_MAX_AXES] = {0, 0, 0};
    uint8_t clamped = 0;
    const uint8_t active = enable && d->latched_faults == 0;
    if (active) {
        const int32_t limit = d->config->force_limit_un;
        for (uint8_t i = 0; i < d->config->axes; ++i) {
            const int32_t f = (int32_t)hfw_load_u32(payload + 8 + (size_t)4 * i);
            if (f > limit || f < -limit) clamped = 1;
            force_un[i] = f > limit ? limit : f < -limit ? -limit : f;
        }
    }
    output(d, force_un, active);
    /* 4.6: this command took effect now, whatever it set (zero too) */
    const uint64_t applied_us = d->board.now_us(d->board.context);
    const uint32_t sequence = hfw_load_u32(payload);
    uint16_t status = 0;
    if (d->command_seen) {
        if (sequence != d->command_sequence + 1u) status |= HFW_STATUS_COMMAND_GAP;
        /* more than 1.5 periods since the last: that force was held too long */
        const uint32_t late_us = d->config->period_us + d->config->period_us / 2u;
        if (now_us - d->command_arrival_us > late_us) {
            status |= HFW_STATUS_COMMAND_LATE;
        }
    }
    d->previous_sequence = d->applied_sequence;
    d->previous_us = d->applied_us;
    d->applied_known = d->applied_known == 0 ? 1 : 2;
    d->applied_sequence = sequence;
    d->applied_us = applied_us;
    d->force_clamped = clamped;
    d->command_status = status;
    d->command_seen = 1;
    d->command_sequence = sequence;
    d->command_arrival_us = now_us;
}

/* ---- dispatch: the table of 5.6 ---- */

enum hfw_reply hfw_device_receive(struct hfw_device* d, const uint8_t* frame, size_t size,
                                  uint64_t now_us, uint8_t* out, size_t* out_size) {
    *out_size = 0;
    if (!frame_intact(frame, size)) {
        ++d->dropped_frames;
        return HFW_REPLY_NONE;
    }
    const uint8_t version = frame[1], type = frame[2], payload_size = frame[3];
    const uint32_t session = hfw_load_u32(frame + 4);
    const uint8_t* payload = frame + HFW_HEADER_SIZE;
    uint8_t code = 0;
    uint32_t detail = 0;
    const int frozen = type == HFW_HELLO || type == HFW_ERROR;
    if (frozen ? version != HFW_FROZEN_VERSION
               : (version < HFW_MIN_VERSION || version > d->config->max_version)) {
        code = HFW_ERROR_BAD_VERSION;
        detail = version_range(d);
    } else if (!is_message_type(type)) {
        code = HFW_ERROR_UNKNOWN_TYPE;
    } else if (!is_host_to_device(type)) {
        code = HFW_ERROR_UNEXPECTED_TYPE;
    } else {
        code = payload_error(type, payload, payload_size);
        if (code == 0 && type == HFW_HELLO && session == 0) code = HFW_ERROR_BAD_FIELD; /* 4.1 */
    }
    if (code == 0 && type == HFW_HELLO) return on_hello(d, session, payload, out, out_size);
    if (code == 0 && !d->session_open) code = HFW_ERROR_NO_SESSION;
    if (code == 0 && session != d->session) code = HFW_ERROR_WRONG_SESSION;
    if (code == 0 && version != d->version) { /* 3.2: the session's version only */
        code = HFW_ERROR_BAD_VERSION;
        detail = version_range(d);
    }
    if (code == 0 && type == HFW_COMMAND && payload[5] != d->config->axes) {
        code = HFW_ERROR_WRONG_AXES;
        detail = d->config->axes;
    }
    if (code != 0) {
        *out_size = error_reply(d, session, type, code, detail, out);
        return HFW_REPLY_FRAME;
    }
    switch (type) {
        case HFW_CONFIGURE:
            *out_size = on_configure(d, payload, out);
            return HFW_REPLY_FRAME;
        case HFW_COMMAND:
            on_command(d, payload, now_us);
            return HFW_REPLY_SAMPLE;
        case HFW_POLL:
            d->command_status = 0;
            return HFW_REPLY_SAMPLE;
        default: /* bye */
            close_session(d);
            *out_size = finish(d->version, HFW_BYE_ACK, 0, session, out);
            return HFW_REPLY_FRAME;
    }
}

/* ---- 4.6 sample ---- */

uint32_t hfw_device_sample_begin(const struct hfw_device* d, uint64_t time_us,
                                 uint16_t sensor_status, uint8_t* out) {
    uint8_t* p = out + HFW_HEADER_SIZE;
    uint16_t status =
        (uint16_t)(sensor_status & (HFW_STATUS_ENCODER_STALE | HFW_STATUS_ENCODER_JUMP));
    status |= d->command_status; /* the answer to a command says how it came; 0 for a poll */
    if (d->force_active) status |= HFW_STATUS_FORCE_ACTIVE;
    if (d->force_clamped) status |= HFW_STATUS_FORCE_CLAMPED;
    const uint8_t axes = d->config->axes;
    out[0] = HFW_MAGIC;
    out[1] = d->version;
    out[2] = HFW_SAMPLE;
    out[3] = (uint8_t)HFW_SAMPLE_PAYLOAD(axes);
    hfw_store_u32(out + 4, d->session);
    hfw_store_u32(p, d->command_seen ? d->command_sequence : 0u);
    hfw_store_u32(p + 4, d->sample_sequence);
    hfw_store_u64(p + 8, time_us);
    hfw_store_u16(p + 16, status);
    hfw_store_u16(p + 18, d->latched_faults);
    p[20] = axes;
    uint8_t lag = 0;
    uint16_t age_us = 0;
    if (d->version >= 2) {
        lag = HFW_APPLIED_LAG_NONE;
        age_us = HFW_APPLIED_AGE_UNKNOWN;
        /* the command in effect at time_us: the last one, or the one before if the last took
           effect after time_us */
        uint32_t sequence = d->applied_sequence;
        uint64_t applied_us = d->applied_us;
        uint8_t known = d->applied_known > 0;
        if (known && applied_us > time_us) {
            sequence = d->previous_sequence;
            applied_us = d->previous_us;
            known = d->applied_known > 1 && applied_us <= time_us;
        }
        const uint32_t behind = d->command_sequence - sequence;
        if (known && behind <= HFW_MAX_APPLIED_LAG) {
            lag = (uint8_t)behind;
            const uint64_t age = time_us - applied_us;
            age_us = age >= HFW_APPLIED_AGE_UNKNOWN ? HFW_APPLIED_AGE_UNKNOWN : (uint16_t)age;
        }
    }
    p[21] = lag;
    hfw_store_u16(p + 22, age_us);
    return hfw_crc32c_update(HFW_CRC32C_START, out, HFW_SAMPLE_COUNTS_OFFSET);
}

void hfw_device_sample_counts(const struct hfw_device* d, const int64_t counts[HFW_MAX_AXES],
                              uint8_t* out) {
    uint8_t* c = out + HFW_SAMPLE_COUNTS_OFFSET;
    for (uint8_t i = 0; i < d->config->axes; ++i) {
        hfw_store_u64(c + (size_t)8 * i, (uint64_t)counts[i]);
    }
}

size_t hfw_device_sample_close(struct hfw_device* d, uint32_t crc_state, uint8_t* out) {
    const size_t crc_at = HFW_SAMPLE_COUNTS_OFFSET + (size_t)8 * d->config->axes;
    hfw_store_u32(out + crc_at, crc_state ^ HFW_CRC32C_START);
    ++d->sample_sequence;
    d->command_status = 0;
    return crc_at + HFW_CRC_SIZE;
}

size_t hfw_device_sample_end(struct hfw_device* d, uint32_t crc_state,
                             const int64_t counts[HFW_MAX_AXES], uint8_t* out) {
    hfw_device_sample_counts(d, counts, out);
    crc_state =
        hfw_crc32c_update(crc_state, out + HFW_SAMPLE_COUNTS_OFFSET, (size_t)8 * d->config->axes);
    return hfw_device_sample_close(d, crc_state, out);
}

size_t hfw_device_sample(struct hfw_device* d, const int64_t counts[HFW_MAX_AXES], uint64_t time_us,
                         uint16_t sensor_status, uint8_t* out) {
    return hfw_device_sample_end(d, hfw_device_sample_begin(d, time_us, sensor_status, out), counts,
                                 out);
}

int hfw_device_paced(const struct hfw_device* d) {
    return d->session_open && d->version >= 3 && d->config->paced;
}

/* ---- 5.4, 5.5 ---- */

int hfw_device_check_watchdog(struct hfw_device* d, uint64_t now_us) {
#ifdef HFW_BROKEN_NO_WATCHDOG /* the conformance tester's own test: a firmware that must fail */
    (void)d;
    (void)now_us;
    return 0;
#endif
    if (!d->session_open || !d->command_seen || (d->latched_faults & HFW_FAULT_WATCHDOG) != 0) {
        return 0;
    }
    if (now_us - d->command_arrival_us < d->watchdog_timeout_us) return 0;
    d->latched_faults |= HFW_FAULT_WATCHDOG;
    zero_force(d); /* not a command: the command in effect stays the one named */
    ++d->watchdog_trips;
    return 1;
}

void hfw_device_set_fault_causes(struct hfw_device* d, uint16_t present) {
    d->fault_causes = present;
    if ((present & ~d->latched_faults) == 0) return;
    d->latched_faults |= present;
    zero_force(d);
}

uint64_t hfw_f64_bits(float value) {
    uint32_t f;
    memcpy(&f, &value, sizeof f);
    const uint64_t sign = (uint64_t)(f >> 31) << 63;
    const uint32_t exponent = (f >> 23) & 0xFFu;
    uint32_t mantissa = f & 0x7FFFFFu;
    if (exponent == 0xFFu) { /* infinity or NaN */
        return sign | (0x7FFull << 52) | ((uint64_t)mantissa << 29);
    }
    if (exponent == 0) {
        if (mantissa == 0) return sign; /* zero */
        /* subnormal: normalise; the double's exponent range holds it */
        int shift = 0;
        while ((mantissa & 0x800000u) == 0) {
            mantissa <<= 1;
            ++shift;
        }
        mantissa &= 0x7FFFFFu;
        return sign | ((uint64_t)(1 - 127 - shift + 1023) << 52) | ((uint64_t)mantissa << 29);
    }
    return sign | ((uint64_t)(exponent - 127 + 1023) << 52) | ((uint64_t)mantissa << 29);
}
