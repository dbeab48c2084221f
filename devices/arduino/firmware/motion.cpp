#include "motion.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>

#define STEP_MASK 0x3F
#define DV ((int16_t)(ACCEL_STEPS / MOTION_HZ))  // velocity change per update [steps/s]
#define BRAKE_ZONE 64                              // > V_MAX^2 / (2 ACCEL) [steps]

// shared with the step interrupt
static volatile uint16_t s_inc[N_CHANNELS];  // phase increment per tick [1/65536 step]
static volatile uint16_t s_acc[N_CHANNELS];
static volatile int16_t s_pos[N_CHANNELS];
static volatile int8_t s_dir[N_CHANNELS];    // +1 / -1, matches the DIR pin
static volatile uint8_t s_active;            // bit i: channel i has a non-zero increment
// main loop only
static int16_t s_target[N_CHANNELS];
static int16_t s_vel[N_CHANNELS];            // [steps/s]

#define CHANNEL_TICK(i)                       \
  if (s_inc[i]) {                             \
    uint16_t a = s_acc[i] + s_inc[i];         \
    if (a < s_acc[i]) {                       \
      out |= (1 << i);                        \
      s_pos[i] += s_dir[i];                   \
    }                                         \
    s_acc[i] = a;                             \
  }

ISR(TIMER1_COMPA_vect) {
  PORTA &= ~STEP_MASK;  // end the pulses raised one tick (100 us) ago
  if (!s_active) {
    TIMSK1 &= ~(1 << OCIE1A);  // idle: no tick until a channel moves again
    return;
  }
  uint8_t out = 0;
  CHANNEL_TICK(0)
  CHANNEL_TICK(1)
  CHANNEL_TICK(2)
  CHANNEL_TICK(3)
  CHANNEL_TICK(4)
  CHANNEL_TICK(5)
  PORTA |= out;
}

void motion_begin() {
  PORTL |= 0x01;  // EN high: drivers off
  DDRL |= 0x01;
  PORTA &= ~STEP_MASK;
  DDRA |= STEP_MASK;
  PORTC |= STEP_MASK;  // DIR high = +1
  DDRC |= STEP_MASK;
  for (uint8_t i = 0; i < N_CHANNELS; ++i) {
    s_dir[i] = 1;
    s_inc[i] = s_acc[i] = 0;
    s_pos[i] = s_target[i] = s_vel[i] = 0;
  }
  s_active = 0;
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    TCCR1A = 0;
    TCCR1B = (1 << WGM12) | (1 << CS10);  // CTC, clk/1
    OCR1A = (uint16_t)(F_CPU / TICK_HZ - 1);
    TCNT1 = 0;
    TIMSK1 = (1 << OCIE1A);
  }
}

void motion_enable_drivers(bool on) {
  if (on) PORTL &= ~0x01;
  else PORTL |= 0x01;
}

void motion_positions(int16_t *pos) {
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    for (uint8_t i = 0; i < N_CHANNELS; ++i) pos[i] = s_pos[i];
  }
}

void motion_halt() {
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    for (uint8_t i = 0; i < N_CHANNELS; ++i) {
      s_inc[i] = 0;
      s_vel[i] = 0;
      s_target[i] = s_pos[i];
    }
    s_active = 0;
  }
}

void motion_declare(const int16_t *pos) {
  ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
    for (uint8_t i = 0; i < N_CHANNELS; ++i) {
      s_inc[i] = s_acc[i] = 0;
      s_vel[i] = 0;
      s_pos[i] = s_target[i] = pos[i];
    }
    s_active = 0;
  }
}

void motion_set_targets(const int16_t *target) {
  for (uint8_t i = 0; i < N_CHANNELS; ++i) s_target[i] = target[i];
}

bool motion_moving() {
  for (uint8_t i = 0; i < N_CHANNELS; ++i)
    if (s_vel[i]) return true;
  return false;
}

// Next velocity of one channel [steps/s] from its position error [steps] and velocity: accelerate
// toward the target at ACCEL, brake when v^2 > 2 a |e|, never faster than |e| steps per 2 updates (so
// the update after the arriving step comes before another one), stop on the target. A NEMA17 starts
// and stops without losing steps far above V_MAX (0.6 rev/s), so the last-step stop is safe.
static int16_t next_velocity(int32_t err, int16_t v) {
  if (err == 0) return 0;
  int8_t s = err > 0 ? 1 : -1;
  uint32_t abserr = err > 0 ? err : -err;
  if ((int32_t)v * s < 0) return v + s * DV;  // heading away: turn around
  uint32_t vv = (uint32_t)((int32_t)v * v);
  bool brake = abserr < BRAKE_ZONE && vv > 2UL * ACCEL_STEPS * abserr;  // v^2 > 2 a |e|
  int16_t w = brake ? v - s * DV : v + s * DV;
  if (brake && (int32_t)w * s <= 0) w = s * DV;  // keep creeping toward the target
  int16_t cap = abserr < V_MAX_STEPS / (MOTION_HZ / 2) ? (int16_t)(abserr * (MOTION_HZ / 2)) : V_MAX_STEPS;
  if (w > cap) w = cap;
  if (w < -cap) w = -cap;
  return w;
}

void motion_update(bool enabled) {
  for (uint8_t i = 0; i < N_CHANNELS; ++i) {
    int16_t pos;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { pos = s_pos[i]; }
    int16_t v = enabled ? next_velocity((int32_t)s_target[i] - pos, s_vel[i]) : 0;
    if (v == s_vel[i]) continue;
    s_vel[i] = v;
    uint16_t speed = v >= 0 ? v : -v;
    uint16_t inc = (uint16_t)(((uint32_t)speed * 53687UL) >> 13);  // speed * 65536 / TICK_HZ
    int8_t dir = v >= 0 ? 1 : -1;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
      if (v != 0 && dir != s_dir[i]) {  // new direction: set DIR, restart the phase (>= 2 ticks of setup)
        if (dir > 0) PORTC |= (1 << i);
        else PORTC &= ~(1 << i);
        s_dir[i] = dir;
        s_acc[i] = 0;
      }
      s_inc[i] = inc;
      if (inc) s_active |= (1 << i);
      else s_active &= ~(1 << i);
      if (s_active) TIMSK1 |= (1 << OCIE1A);  // the step tick runs only while a channel moves
    }
  }
}
