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
