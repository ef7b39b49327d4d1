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

/* The receiver, fed one byte at a time as the bytes arrive. */
struct hfw_cobs_decoder {
    uint8_t frame[HFW_MAX_FRAME_SIZE];
    uint8_t size;         /* decoded bytes so far */
    uint8_t remaining;    /* data bytes left in the current block; 0: next is a code byte */
    uint8_t zero_pending; /* the current block ends in an implied 0x00 */
    uint8_t encoded;      /* encoded bytes since the last delimiter (saturates) */
    uint8_t broken;       /* too long, or a delimiter inside a block: drop at the delimiter */
    uint16_t dropped;     /* frames dropped as broken (wraps) */
};

void hfw_cobs_reset(struct hfw_cobs_decoder* d);

/* Takes one byte; returns 1 when it was the delimiter after a whole frame, which is then in
   d->frame[0 .. d->size) until the next call. Empty frames (two delimiters in a row) are
   ignored; a frame longer than HFW_MAX_FRAME_SIZE or cut inside a block is counted in
   d->dropped and never returned. */
int hfw_cobs_push(struct hfw_cobs_decoder* d, uint8_t byte);

#ifdef __cplusplus
}
#endif

#endif
