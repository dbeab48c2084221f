// USART0 driver for the host link at 1 Mbaud (U2X, UBRR = 1: exact at 16 MHz), interrupt-driven and
// frame-aware: the RX interrupt splits the byte stream at 0x00 into RX_SLOTS frame buffers (about 40
// cycles per byte, so the main loop runs once per frame, not once per byte); oversized input is
// discarded up to its delimiter and counted; a frame that finds every slot full is dropped and counted.
// TX is a ring drained by the UDRE interrupt. (Replaces the core's HardwareSerial, whose per-byte
// cost is more than the 160 cycles a byte lasts at 1 Mbaud.)
#ifndef CDPR_UART_H
#define CDPR_UART_H

#include <stdint.h>
#include "protocol.h"

#define RX_SLOTS 8  // power of two; absorbs a burst of 8 frames (a USB-serial bridge delivers up to 3 per 1 ms USB frame)
#define TX_SIZE 128  // power of two

void uart_begin();
// Oldest complete frame (COBS bytes without the delimiter) or 0; *len receives its length.
uint8_t *uart_frame(uint8_t *len);
void uart_release();  // done with the frame uart_frame returned
uint8_t uart_tx_free();
void uart_write(const uint8_t *data, uint8_t n);  // caller checks uart_tx_free() first
uint16_t uart_overflow_count();  // oversized frames
uint16_t uart_busy_count();      // frames dropped with every slot full
bool uart_rx_pending();          // a complete frame is waiting

#endif
