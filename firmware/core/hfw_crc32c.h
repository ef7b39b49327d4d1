/* CRC-32C (Castagnoli), as docs/protocol.md section 3.3 specifies: reflected polynomial
   0x82F63B78, init and xorout 0xFFFFFFFF; hfw_crc32c("123456789", 9) == 0xE3069283. */
#ifndef HFW_CRC32C_H
#define HFW_CRC32C_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One byte at a time through a 256-entry table: 35 AVR cycles a byte with the table in flash
   (1 KB), against 232 for the bitwise code of the protocol's appendix (docs/firmware.md). */
uint32_t hfw_crc32c(const uint8_t* data, size_t size);

/* The same in parts: start from HFW_CRC32C_START, feed each part to hfw_crc32c_update(), and
   the CRC is the last state ^ HFW_CRC32C_START. */
#define HFW_CRC32C_START 0xFFFFFFFFu
uint32_t hfw_crc32c_update(uint32_t state, const uint8_t* data, size_t size);

#ifdef __cplusplus
}
#endif

#endif
