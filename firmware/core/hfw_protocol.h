/* The hapticd device protocol's constants (docs/protocol.md; the host's own in
   include/hapticd/device/protocol/). Section numbers below are the protocol's. */
#ifndef HFW_PROTOCOL_H
#define HFW_PROTOCOL_H

/* 3.1 frames */
#define HFW_MAGIC 0x48u
#define HFW_HEADER_SIZE 8u
#define HFW_CRC_SIZE 4u
#define HFW_MIN_FRAME_SIZE (HFW_HEADER_SIZE + HFW_CRC_SIZE)
#define HFW_MAX_PAYLOAD_SIZE 48u
#define HFW_MAX_FRAME_SIZE (HFW_MIN_FRAME_SIZE + HFW_MAX_PAYLOAD_SIZE)
#define HFW_MAX_AXES 3u

/* 3.2 versions: this firmware speaks 1 to 3; hello and error always carry 1. */
#define HFW_MIN_VERSION 1u
#define HFW_MAX_VERSION 3u
#define HFW_FROZEN_VERSION 1u

/* 4 message types */
#define HFW_HELLO 0x01u
#define HFW_CONFIGURE 0x02u
#define HFW_COMMAND 0x03u
#define HFW_POLL 0x04u
#define HFW_BYE 0x05u
#define HFW_IDENTITY 0x81u
#define HFW_CONFIGURE_ACK 0x82u
#define HFW_SAMPLE 0x83u
#define HFW_BYE_ACK 0x85u
#define HFW_ERROR 0xFFu

/* payload sizes */
#define HFW_HELLO_PAYLOAD 4u
#define HFW_IDENTITY_PAYLOAD 44u
#define HFW_CONFIGURE_PAYLOAD 4u
#define HFW_COMMAND_PAYLOAD(axes) (8u + 4u * (axes))
#define HFW_SAMPLE_PAYLOAD(axes) (24u + 8u * (axes))
#define HFW_ERROR_PAYLOAD 8u

/* 4.2 identity flags (version 3) */
#define HFW_IDENTITY_PACED 0x01u

/* 4.5 command flags */
#define HFW_COMMAND_ENABLE 0x01u
#define HFW_COMMAND_CLEAR_FAULTS 0x02u

/* 4.6 sample status bits */
#define HFW_STATUS_FORCE_ACTIVE 0x0001u
#define HFW_STATUS_FORCE_CLAMPED 0x0002u
#define HFW_STATUS_ENCODER_STALE 0x0004u
#define HFW_STATUS_ENCODER_JUMP 0x0008u
#define HFW_STATUS_COMMAND_LATE 0x0010u
#define HFW_STATUS_COMMAND_GAP 0x0020u

/* 4.6 latched fault bits */
#define HFW_FAULT_WATCHDOG 0x0001u
#define HFW_FAULT_ENCODER 0x0010u
#define HFW_FAULT_INTERNAL 0x0080u

/* 4.6 the command in effect (version 2) */
#define HFW_APPLIED_LAG_NONE 0xFFu
#define HFW_MAX_APPLIED_LAG 0xFEu
#define HFW_APPLIED_AGE_UNKNOWN 0xFFFFu

/* 4.10 error codes */
#define HFW_ERROR_UNKNOWN_TYPE 1u
#define HFW_ERROR_UNEXPECTED_TYPE 2u
#define HFW_ERROR_BAD_LENGTH 3u
#define HFW_ERROR_BAD_FIELD 4u
#define HFW_ERROR_BAD_VERSION 5u
#define HFW_ERROR_UNSUPPORTED_VERSION 6u
#define HFW_ERROR_NO_SESSION 7u
#define HFW_ERROR_WRONG_SESSION 8u
#define HFW_ERROR_WRONG_AXES 9u
#define HFW_ERROR_OUT_OF_RANGE 10u

/* 5.4 the watchdog's range */
#define HFW_MAX_WATCHDOG_TIMEOUT_US 1000000u

#endif
