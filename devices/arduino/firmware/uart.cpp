#include "uart.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>

static uint8_t s_slot[RX_SLOTS][MAX_FRAME];
static volatile uint8_t s_slot_len[RX_SLOTS];
static volatile uint8_t s_head, s_count;  // oldest complete slot, number of complete slots
// receiver state (RX interrupt only): between frames, storing into s_wp, or skipping to the next 0x00
enum { RX_IDLE, RX_STORE, RX_SKIP };
static uint8_t s_state = RX_IDLE;
static uint8_t *s_wp;
static uint8_t s_len;
static volatile uint16_t s_overflow, s_busy;

static uint8_t s_tx[TX_SIZE];
static volatile uint8_t s_tx_head, s_tx_tail;

ISR(USART0_RX_vect) {
  uint8_t b = UDR0;
  if (b == 0) {  // delimiter
    if (s_state == RX_STORE && s_len > 0) {
      s_slot_len[(s_head + s_count) & (RX_SLOTS - 1)] = s_len;
      ++s_count;
    }
    s_state = RX_IDLE;
    return;
  }
  if (s_state == RX_STORE) {
    if (s_len < MAX_FRAME) {
      *s_wp++ = b;
      ++s_len;
    } else {  // oversized or unterminated: skip to the next delimiter
      if (s_overflow != 0xFFFF) ++s_overflow;
      s_state = RX_SKIP;
    }
  } else if (s_state == RX_IDLE) {  // first byte of a frame: take a free slot, or drop the frame
    if (s_count < RX_SLOTS) {
      s_wp = s_slot[(s_head + s_count) & (RX_SLOTS - 1)];
      *s_wp++ = b;
      s_len = 1;
      s_state = RX_STORE;
    } else {
      if (s_busy != 0xFFFF) ++s_busy;
      s_state = RX_SKIP;
    }
  }
}

ISR(USART0_UDRE_vect) {
  uint8_t t = s_tx_tail;
  if (t != s_tx_head) {
    UDR0 = s_tx[t];
    s_tx_tail = t = (t + 1) & (TX_SIZE - 1);
  }
  if (t == s_tx_head) UCSR0B &= ~(1 << UDRIE0);
}

void uart_begin() {
  UCSR0A = (1 << U2X0);
  UBRR0H = 0;
  UBRR0L = 1;                             // 16 MHz / (8 * (1 + 1)) = 1 Mbaud
  UCSR0C = (1 << UCSZ01) | (1 << UCSZ00);  // 8N1
  UCSR0B = (1 << RXEN0) | (1 << TXEN0) | (1 << RXCIE0);
}

uint8_t *uart_frame(uint8_t *len) {
  if (!s_count) return 0;
  *len = s_slot_len[s_head];  // the slot stays ours until uart_release()
  return s_slot[s_head];
}

void uart_release() {
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    s_head = (s_head + 1) & (RX_SLOTS - 1);
    --s_count;
  }
}

bool uart_rx_pending() { return s_count != 0; }

uint8_t uart_tx_free() { return (uint8_t)((s_tx_tail - s_tx_head - 1) & (TX_SIZE - 1)); }

void uart_write(const uint8_t *data, uint8_t n) {
  uint8_t h = s_tx_head;
  while (n--) {
    s_tx[h] = *data++;
    h = (h + 1) & (TX_SIZE - 1);
  }
  s_tx_head = h;
  UCSR0B |= (1 << UDRIE0);
}

uint16_t uart_overflow_count() {
  uint16_t v;
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { v = s_overflow; }
  return v;
}

uint16_t uart_busy_count() {
  uint16_t v;
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { v = s_busy; }
  return v;
}
