#include "hfw_cobs.h"

size_t hfw_cobs_encode(const uint8_t* frame, size_t size, uint8_t* out) {
    size_t code_at = 0, write_at = 1;
    uint8_t code = 1;
    for (size_t i = 0; i < size; ++i) {
        if (frame[i] == 0) {
            out[code_at] = code;
            code_at = write_at++;
            code = 1;
        } else {
            out[write_at++] = frame[i];
            if (++code == 0xFF) {
                out[code_at] = code;
                code_at = write_at++;
                code = 1;
            }
        }
    }
    out[code_at] = code;
    out[write_at++] = 0x00;
    return write_at;
}

void hfw_cobs_reset(struct hfw_cobs_decoder* d) {
    d->size = 0;
    d->remaining = 0;
    d->zero_pending = 0;
    d->encoded = 0;
    d->broken = 0;
}

static void append(struct hfw_cobs_decoder* d, uint8_t byte) {
    if (d->size == HFW_MAX_FRAME_SIZE) {
        d->broken = 1;
        return;
    }
    d->frame[d->size++] = byte;
}

int hfw_cobs_push(struct hfw_cobs_decoder* d, uint8_t byte) {
    if (byte == 0x00) {
        const int whole = d->encoded > 0 && !d->broken && d->remaining == 0;
        if (d->encoded > 0 && !whole) ++d->dropped;
        d->remaining = 0;
        d->zero_pending = 0;
        d->encoded = 0;
        d->broken = 0;
        if (!whole) d->size = 0;
        return whole;
    }
    if (d->encoded == 0) d->size = 0; /* a new frame: the last one is no longer kept */
    if (d->encoded < 0xFF) ++d->encoded;
    if (d->broken) return 0;
    if (d->remaining == 0) { /* a code byte */
        if (d->zero_pending) append(d, 0x00);
        d->zero_pending = byte != 0xFF;
        d->remaining = (uint8_t)(byte - 1);
        return 0;
    }
    append(d, byte);
    --d->remaining;
    return 0;
}
