/* Little-endian fields at byte offsets (docs/protocol.md section 2): frames are read and
   written byte by byte, never cast to structs, so a frame may sit at any alignment. */
#ifndef HFW_WIRE_H
#define HFW_WIRE_H

#include <stdint.h>
#include <string.h>

static inline uint16_t hfw_load_u16(const uint8_t* p) {
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}

static inline uint32_t hfw_load_u32(const uint8_t* p) {
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline void hfw_store_u16(uint8_t* p, uint16_t v) {
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static inline void hfw_store_u32(uint8_t* p, uint32_t v) {
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static inline void hfw_store_u64(uint8_t* p, uint64_t v) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    /* the wire's order already (the AVR, x86): no 64-bit shifts, which avr-gcc calls out for */
    memcpy(p, &v, sizeof v);
#else
    hfw_store_u32(p, (uint32_t)v);
    hfw_store_u32(p + 4, (uint32_t)(v >> 32));
#endif
}

#endif
