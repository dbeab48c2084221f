// Framing for the host link: CRC-32 (IEEE, as zlib), COBS, and a bounded receive framer.
#ifndef CDPR_LINK_H
#define CDPR_LINK_H

#include <stdint.h>
#include "protocol.h"

uint32_t crc32_update(uint32_t crc, const uint8_t *data, uint8_t n);  // start with 0xFFFFFFFF
uint32_t crc32(const uint8_t *data, uint8_t n);

// COBS-encode n (< 254) bytes into out (n + 1 bytes, no zero); returns the encoded length.
uint8_t cobs_encode(const uint8_t *in, uint8_t n, uint8_t *out);
// Decode in place; returns the decoded length, or -1 when a code byte runs past the end.
int16_t cobs_decode_inplace(uint8_t *buf, uint8_t n);

struct LinkCounters {
  uint16_t crc, cobs, shortframe, malformed, stale, rejected, watchdog_trips, rx_frames, tx_dropped;
};

// One received frame (COBS bytes without the delimiter) -> payload length (> 0, payload decoded in
// place in buf) when COBS and CRC-32 check out, 0 otherwise (the error is counted).
uint8_t frame_decode(uint8_t *buf, uint8_t n, LinkCounters &counters);

static inline void inc_sat(uint16_t &c) { if (c != 0xFFFF) ++c; }

#endif
