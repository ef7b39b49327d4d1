/* COBS framing with a 0x00 delimiter, the serial transport of docs/protocol.md section 6.3
   (Cheshire and Baker, 1999). */
#ifndef HFW_COBS_H
#define HFW_COBS_H

#include <stddef.h>
#include <stdint.h>

#include "hfw_protocol.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The most bytes a frame takes on the line: the frame, one code byte (frames are shorter
   than 254 bytes) and the delimiter. */
#define HFW_COBS_MAX_ENCODED (HFW_MAX_FRAME_SIZE + 2)

/* Writes `size` bytes of `frame` (size <= HFW_MAX_FRAME_SIZE) to `out` as COBS followed by
   the 0x00 delimiter; returns the bytes written (size + 2). */
size_t hfw_cobs_encode(const uint8_t* frame, size_t size, uint8_t* out);

/* The same in parts, so that the front of a frame can go out before its end is known: a
   block's code byte is written when the block ends, so out[0 .. hfw_cobs_final()) is final
   while the rest is still to come. */
struct hfw_cobs_encoder {
    uint8_t* out;
    uint8_t code_at;  /* where the open block's code byte goes */
    uint8_t write_at; /* where the next byte goes */
    uint8_t code;     /* the open block's code so far */
};

void hfw_cobs_start(struct hfw_cobs_encoder* e, uint8_t* out);
void hfw_cobs_put(struct hfw_cobs_encoder* e, const uint8_t* bytes, size_t size);
/* The bytes of out that no later put can change. */
static inline uint8_t hfw_cobs_final(const struct hfw_cobs_encoder* e) { return e->code_at; }
/* Closes the last block and writes the delimiter; returns the encoded size. */
size_t hfw_cobs_finish(struct hfw_cobs_encoder* e);

/* The receiver, fed one byte at a time as the bytes arrive. Its state is a few bytes, which a
   board copies into a local variable while bytes come (the compiler then keeps it in
   registers); the frame is in a buffer of the caller's. */
struct hfw_cobs_decoder {
    uint8_t* frame;       /* HFW_MAX_FRAME_SIZE bytes */
    uint8_t size;         /* decoded bytes so far */
    uint8_t remaining;    /* data bytes left in the current block; 0: next is a code byte */
    uint8_t zero_pending; /* the current block ends in an implied 0x00 */
    uint8_t encoded;      /* encoded bytes since the last delimiter (saturates) */
    uint8_t broken;       /* too long, or a delimiter inside a block: drop at the delimiter */
    uint16_t dropped;     /* frames dropped as broken (wraps) */
};

/* Starts a receiver on `frame` (HFW_MAX_FRAME_SIZE bytes); hfw_cobs_reset() forgets a
   partial frame. */
void hfw_cobs_init(struct hfw_cobs_decoder* d, uint8_t* frame);
void hfw_cobs_reset(struct hfw_cobs_decoder* d);

/* Takes one byte; returns 1 when it was the delimiter after a whole frame, which is then in
   d->frame[0 .. d->size) until the next call. Empty frames (two delimiters in a row) are
   ignored; a frame longer than HFW_MAX_FRAME_SIZE or cut inside a block is counted in
   d->dropped and never returned. Inline: at 2 Mbaud a byte comes every 80 cycles of an
   ATmega328P, and a call per byte costs half of that; with the decoder in a local variable
   the compiler keeps it in registers. */
static inline int hfw_cobs_push(struct hfw_cobs_decoder* d, uint8_t byte) {
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
        d->remaining = (uint8_t)(byte - 1);
        if (!d->zero_pending) {
            d->zero_pending = byte != 0xFF;
            return 0;
        }
        d->zero_pending = byte != 0xFF;
        byte = 0x00; /* the block before ended in an implied zero: append it */
    } else {
        --d->remaining;
    }
    if (d->size == HFW_MAX_FRAME_SIZE) {
        d->broken = 1;
        return 0;
    }
    d->frame[d->size++] = byte;
    return 0;
}

#ifdef __cplusplus
}
#endif

#endif
