// Six step/dir channels: a TICK_HZ timer interrupt emits step pulses from per-channel phase
// accumulators (DDA); motion_update() at MOTION_HZ moves each velocity toward its target with the
// acceleration and speed limits (brakes when v^2 > 2 a |error|).
//
// Pins (Arduino Mega2560): STEP0..5 = PA0..PA5 (D22..D27), DIR0..5 = PC0..PC5 (D37..D32),
// EN (active low, all drivers) = PL0 (D49). Positive steps haul the cable in (DIR high).
#ifndef CDPR_MOTION_H
#define CDPR_MOTION_H

#include <stdint.h>
#include "protocol.h"

void motion_begin();                       // pins and the step timer; drivers disabled, no motion
void motion_enable_drivers(bool on);
void motion_declare(const int16_t *pos);   // set positions (homing), targets = positions, v = 0
void motion_set_targets(const int16_t *target);
void motion_halt();                        // stop now: v = 0, targets = positions
void motion_update(bool enabled);          // call at MOTION_HZ
void motion_positions(int16_t *pos);       // atomic snapshot
bool motion_moving();

#endif
