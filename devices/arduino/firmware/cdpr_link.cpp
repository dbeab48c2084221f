// CDPR robot link firmware for the Arduino Mega2560: six step/dir stepper channels with acceleration
// limits, six FSR ADC inputs (A0..A5), a framed binary protocol (COBS + CRC-32, sequence numbers,
// boot id) at 1 Mbaud on USART0, and a watchdog that stops the motors when no valid host frame arrived
// for WATCHDOG_MS. Every host frame except STOP must carry a fresh sequence number (stale or duplicate
// frames are rejected and counted); STOP is always obeyed. Every accepted host frame is answered
// (TELEMETRY, or HELLO_REPLY / DIAG_REPLY).
#include <Arduino.h>
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/sleep.h>
#include <string.h>

#include "link.h"
#include "motion.h"
#include "protocol.h"
#include "uart.h"

static LinkCounters g_counters;
static uint16_t g_boot_id;
static uint16_t g_tx_seq;
static uint16_t g_last_seq;
static bool g_seq_known;
static bool g_homed, g_stopped, g_watchdog_stop;
static uint16_t g_silent_ms;     // motion ticks since the last valid host frame
static uint16_t g_handle_max_us;  // longest frame handling
static uint32_t g_errors_at_diag;

static volatile bool g_tick;  // MOTION_HZ tick from timer 3
static volatile uint16_t g_adc[N_CHANNELS];
static volatile uint8_t g_adc_channel;

ISR(TIMER3_COMPA_vect) { g_tick = true; }

ISR(ADC_vect) {  // one sweep of single conversions over A0..A5 (104 us each), started every tick
  g_adc[g_adc_channel] = ADC;
  if (++g_adc_channel < N_CHANNELS) {
    ADMUX = (1 << REFS0) | g_adc_channel;  // AVcc reference
    ADCSRA |= (1 << ADSC);
  }
}

static void adc_begin() {
  ADCSRB = 0;
  ADCSRA = (1 << ADEN) | (1 << ADIE) | (1 << ADPS2) | (1 << ADPS1) | (1 << ADPS0);
}

static void adc_sweep() {
  if (ADCSRA & (1 << ADSC)) return;  // previous sweep still converting
  g_adc_channel = 0;
  ADMUX = (1 << REFS0);
  ADCSRA |= (1 << ADSC);
}

static void tick_begin() {  // timer 3, CTC at MOTION_HZ
  TCCR3A = 0;
  TCCR3B = (1 << WGM32) | (1 << CS31) | (1 << CS30);  // clk/64
  OCR3A = (uint16_t)(F_CPU / 64 / MOTION_HZ - 1);
  TIMSK3 = (1 << OCIE3A);
}

static inline void put16(uint8_t *p, uint16_t v) {
  p[0] = v & 0xFF;
  p[1] = v >> 8;
}
static inline void put32(uint8_t *p, uint32_t v) {
  put16(p, v & 0xFFFF);
  put16(p + 2, v >> 16);
}

static uint32_t error_sum() {
  return (uint32_t)g_counters.crc + g_counters.cobs + g_counters.shortframe + g_counters.malformed +
         g_counters.stale + uart_overflow_count() + uart_busy_count();
}

static uint8_t status_byte() {
  uint8_t s = 0;
  if (g_homed) s |= STATUS_HOMED;
  if (g_watchdog_stop) s |= STATUS_WATCHDOG_STOP;
  if (g_stopped) s |= STATUS_STOPPED;
  if (motion_moving()) s |= STATUS_MOVING;
  if (error_sum() != g_errors_at_diag) s |= STATUS_LINK_ERRORS;
  return s;
}

// Header + body in payload -> CRC, COBS, delimiter -> TX ring. Never blocks: when the ring lacks room
// the frame is dropped and counted (its sequence number is used, so the host sees the gap).
static void send_frame(uint8_t type, uint8_t *payload, uint8_t body_len) {
  put16(payload, ((uint16_t)type << SEQ_BITS) | (g_tx_seq & SEQ_MASK));
  g_tx_seq = (g_tx_seq + 1) & SEQ_MASK;
  uint8_t n = 2 + body_len;
  put32(payload + n, crc32(payload, n));
  n += CRC_SIZE;
  uint8_t wire[MAX_FRAME + 2];
  uint8_t m = cobs_encode(payload, n, wire);
  wire[m++] = 0;
  if (uart_tx_free() < m) {
    inc_sat(g_counters.tx_dropped);
    return;
  }
  uart_write(wire, m);
}

static void send_hello_reply() {
  uint8_t p[2 + HELLO_REPLY_SIZE + CRC_SIZE];
  uint8_t *b = p + 2;
  b[0] = PROTOCOL_VERSION;
  b[1] = FIRMWARE_VERSION_MAJOR;
  b[2] = FIRMWARE_VERSION_MINOR;
  b[3] = FIRMWARE_VERSION_PATCH;
  put16(b + 4, g_boot_id);
  b[6] = N_CHANNELS;
  b[7] = WATCHDOG_MS;
  put16(b + 8, TICK_HZ);
  put16(b + 10, V_MAX_STEPS);
  put32(b + 12, ACCEL_STEPS);
  b[16] = MAX_FRAME;
  send_frame(MSG_HELLO_REPLY, p, HELLO_REPLY_SIZE);
}

static void send_telemetry(uint8_t reply_to, bool rejected) {
  uint8_t p[2 + TELEMETRY_SIZE + CRC_SIZE];
  uint8_t *b = p + 2;
  b[0] = status_byte() | (rejected ? STATUS_REJECTED : 0);
  b[1] = reply_to;
  uint16_t a[N_CHANNELS];
  cli();
  for (uint8_t i = 0; i < N_CHANNELS; ++i) a[i] = g_adc[i] & 0x3FF;
  sei();
  // 6 x 10-bit counts at bits 10i, boot tag in bits 60..63 (little-endian u64)
  uint8_t *w = b + 2;
  w[0] = a[0];
  w[1] = (a[0] >> 8) | (a[1] << 2);
  w[2] = (a[1] >> 6) | (a[2] << 4);
  w[3] = (a[2] >> 4) | (a[3] << 6);
  w[4] = a[3] >> 2;
  w[5] = a[4];
  w[6] = (a[4] >> 8) | (a[5] << 2);
  w[7] = (a[5] >> 6) | ((g_boot_id & 0x0F) << 4);
  int16_t pos[N_CHANNELS];
  motion_positions(pos);
  for (uint8_t i = 0; i < N_CHANNELS; ++i) put16(b + 10 + 2 * i, (uint16_t)pos[i]);
  send_frame(MSG_TELEMETRY, p, TELEMETRY_SIZE);
}

static void send_diag_reply() {
  uint8_t p[2 + DIAG_REPLY_SIZE + CRC_SIZE];
  uint8_t *b = p + 2;
  put32(b, micros());
  put16(b + 4, g_last_seq);
  b[6] = status_byte();
  put16(b + 7, g_handle_max_us);
  const LinkCounters &c = g_counters;
  const uint16_t v[DIAG_COUNTERS] = {c.crc,    c.cobs,           c.shortframe,  uart_overflow_count(),
                                     c.malformed, c.stale,       c.rejected,    c.watchdog_trips,
                                     c.rx_frames, c.tx_dropped,  uart_busy_count()};
  for (uint8_t i = 0; i < DIAG_COUNTERS; ++i) put16(b + 9 + 2 * i, v[i]);
  send_frame(MSG_DIAG_REPLY, p, DIAG_REPLY_SIZE);
  g_errors_at_diag = error_sum();
}

static bool read_steps(const uint8_t *b, int16_t *out) {
  for (uint8_t i = 0; i < N_CHANNELS; ++i) {
    out[i] = (int16_t)((uint16_t)b[2 * i] | ((uint16_t)b[2 * i + 1] << 8));
    if (out[i] > STEP_LIMIT || out[i] < -STEP_LIMIT) return false;
  }
  return true;
}

static bool motion_allowed() { return g_homed && !g_stopped && !g_watchdog_stop; }

// A host seq is fresh when it is 1..2047 ahead of the last accepted one (modulo 4096).
static bool is_fresh(uint16_t seq) {
  uint16_t d = (seq - g_last_seq) & SEQ_MASK;
  return !g_seq_known || (d >= 1 && d <= 2047);
}

static void accept_seq(uint16_t seq) {
  g_last_seq = seq;
  g_seq_known = true;
  g_silent_ms = 0;  // feeds the watchdog
}

static void handle_frame(uint8_t *p, uint8_t n) {
  uint16_t header = (uint16_t)p[0] | ((uint16_t)p[1] << 8);
  uint8_t type = header >> SEQ_BITS;
  uint16_t seq = header & SEQ_MASK;
  uint8_t want;
  switch (type) {
    case MSG_HOME:
    case MSG_COMMAND: want = 2 * N_CHANNELS; break;
    case MSG_HELLO:
    case MSG_STOP:
    case MSG_ENABLE:
    case MSG_HEARTBEAT:
    case MSG_DIAG: want = 0; break;
    default: inc_sat(g_counters.malformed); return;
  }
  if (n < 2 || n - 2 != want) {
    inc_sat(g_counters.malformed);
    return;
  }
  inc_sat(g_counters.rx_frames);
  if (type == MSG_STOP) {  // always obeyed, fresh or not
    motion_halt();
    g_stopped = true;
    if (is_fresh(seq)) accept_seq(seq);
    send_telemetry(seq & 0xFF, false);
    return;
  }
  if (type != MSG_HELLO && !is_fresh(seq)) {
    inc_sat(g_counters.stale);
    send_telemetry(seq & 0xFF, true);
    return;
  }
  accept_seq(seq);
  bool rejected = false;
  int16_t steps[N_CHANNELS];
  switch (type) {
    case MSG_HELLO: send_hello_reply(); return;
    case MSG_DIAG: send_diag_reply(); return;
    case MSG_HOME:
      if (read_steps(p + 2, steps)) {
        motion_declare(steps);
        g_homed = true;
        g_stopped = g_watchdog_stop = false;
        motion_enable_drivers(true);
      } else {
        rejected = true;
      }
      break;
    case MSG_ENABLE:
      if (g_homed) {
        motion_halt();  // resume from where the motors are, never toward an old target
        g_stopped = g_watchdog_stop = false;
      } else {
        rejected = true;
      }
      break;
    case MSG_COMMAND:
      if (motion_allowed() && read_steps(p + 2, steps)) motion_set_targets(steps);
      else rejected = true;
      break;
    default: break;  // HEARTBEAT: only feeds the watchdog
  }
  if (rejected) inc_sat(g_counters.rejected);
  send_telemetry(seq & 0xFF, rejected);
}

static void motion_tick() {
  if (g_silent_ms < 0xFFFF) ++g_silent_ms;
  if (motion_allowed() && g_silent_ms > WATCHDOG_MS) {
    motion_halt();  // host silent: stop now, latch until ENABLE or HOME
    g_watchdog_stop = true;
    inc_sat(g_counters.watchdog_trips);
  }
  motion_update(motion_allowed());
  adc_sweep();
}

void setup() {
  uint16_t boots = eeprom_read_word((uint16_t *)0);
  g_boot_id = boots + 1;
  eeprom_update_word((uint16_t *)0, g_boot_id);
  motion_begin();
  adc_begin();
  tick_begin();
  uart_begin();
  send_hello_reply();  // unsolicited: announces the (new) boot id
}

void loop() {
  uint8_t n;
  uint8_t *frame;
  while ((frame = uart_frame(&n)) != 0) {
    uint32_t t0 = micros();
    uint8_t len = frame_decode(frame, n, g_counters);
    if (len > 0) handle_frame(frame, len);
    uart_release();
    uint32_t dt = micros() - t0;
    if (dt > g_handle_max_us) g_handle_max_us = dt > 0xFFFF ? 0xFFFF : (uint16_t)dt;
  }
  if (g_tick) {
    g_tick = false;
    motion_tick();
  }
  // Idle until the next interrupt (UART, step tick, ADC, timers keep running in IDLE mode). Checking
  // with interrupts off and then "sei; sleep" is atomic: an interrupt after the check still wakes us.
  set_sleep_mode(SLEEP_MODE_IDLE);
  cli();
  if (!uart_rx_pending() && !g_tick) {
    sleep_enable();
    sei();
    sleep_cpu();
    sleep_disable();
  }
  sei();
}
