#include "hfw_cobs.h"

void hfw_cobs_start(struct hfw_cobs_encoder* e, uint8_t* out) {
    e->out = out;
    e->code_at = 0;
    e->write_at = 1;
    e->code = 1;
}

void hfw_cobs_put(struct hfw_cobs_encoder* e, const uint8_t* bytes, size_t size) {
    uint8_t* out = e->out;
    uint8_t code_at = e->code_at, write_at = e->write_at, code = e->code;
    for (size_t i = 0; i < size; ++i) {
        const uint8_t byte = bytes[i];
        if (byte == 0) {
            out[code_at] = code;
            code_at = write_at++;
            code = 1;
        } else {
            out[write_at++] = byte;
            if (++code == 0xFF) {
                out[code_at] = code;
                code_at = write_at++;
                code = 1;
            }
        }
    }
    e->code_at = code_at;
    e->write_at = write_at;
    e->code = code;
}

size_t hfw_cobs_finish(struct hfw_cobs_encoder* e) {
    e->out[e->code_at] = e->code;
    e->out[e->write_at] = 0x00;
    e->code_at = (uint8_t)(e->write_at + 1u); /* everything is final now, the delimiter too */
    return (size_t)e->write_at + 1u;
}

size_t hfw_cobs_encode(const uint8_t* frame, size_t size, uint8_t* out) {
    struct hfw_cobs_encoder e;
    hfw_cobs_start(&e, out);
    hfw_cobs_put(&e, frame, size);
    return hfw_cobs_finish(&e);
}

void hfw_cobs_init(struct hfw_cobs_decoder* d, uint8_t* frame) {
    d->frame = frame;
    d->dropped = 0;
    hfw_cobs_reset(d);
}

void hfw_cobs_reset(struct hfw_cobs_decoder* d) {
    d->size = 0;
    d->remaining = 0;
    d->zero_pending = 0;
    d->encoded = 0;
    d->broken = 0;
}
