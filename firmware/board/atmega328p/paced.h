/* docs/protocol.md 5.8 on this board: in a session the board paces, a sample goes out in two
   parts. Before the period's reading is sampled, its front (everything but the counts: the
   first 32 bytes of a one-axis sample) is written, CRC'd and COBS-encoded into the UART's
   buffer; the period's start sends it, the reading starts while it goes out, and the main
   loop finishes the frame between its last bytes. So the counts wait only for their
   own 12 bytes on the line, not for the whole frame's 46, and the host's next command can come back
   before the next period starts. */
#ifndef HFW_BOARD_PACED_H
#define HFW_BOARD_PACED_H

#include <stdint.h>

#include "hfw_device.h"

/* How long after a period starts (and its front with it) its reading starts (us): so that
   the reading and the frame's end are ready just as the front's last byte leaves. The
   sample's time is then as late in the exchange as it can be. clock_start_periods() takes
   it. */
uint16_t paced_front_lead_us(void);

/* Writes the front of the sample answering the device's last request for the next period's
   reading (the UART must be idle). */
void paced_prepare(const struct hfw_device* d);

/* A front is written, or on its way out. */
uint8_t paced_pending(void);
/* ... and the clock has started sending it: it can no longer change. */
uint8_t paced_started(void);
/* Drops a front that has not started (a request came that it does not answer). */
void paced_cancel(void);

/* Once the clock has started the reading: sends the front byte by byte while the reading
   completes, then finishes the frame (the counts, the CRC) in short steps between bytes and
   sends the rest (bytes that come in meanwhile wait in the UART's receive ring). Returns when the
   frame is out: a period's last byte about 230 us (46 bytes at 2 Mbaud) after its reading started.
 */
void paced_send(struct hfw_device* d);

#endif
