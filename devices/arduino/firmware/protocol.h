// Link protocol constants shared with the host (devices/arduino/messages.py and framing.py; a test
// checks that both sides agree). Payload = u16 LE header (type << 12 | seq) + body; frame =
// COBS(payload + CRC-32 LE) + 0x00.
#ifndef CDPR_PROTOCOL_H
#define CDPR_PROTOCOL_H

#define PROTOCOL_VERSION 1
#define FIRMWARE_VERSION_MAJOR 1
#define FIRMWARE_VERSION_MINOR 0
#define FIRMWARE_VERSION_PATCH 0

#define N_CHANNELS 6
#define SEQ_BITS 12
#define SEQ_MASK 0x0FFF
#define MAX_FRAME 64          // encoded bytes between delimiters; longer input is discarded and counted
#define CRC_SIZE 4
#define STEP_LIMIT 32000      // |position| and |target| bound [steps]

// host -> firmware
#define MSG_HELLO 1
#define MSG_HOME 2            // body: 6 x i16 positions to declare [steps]
#define MSG_COMMAND 3         // body: 6 x i16 targets [steps]
#define MSG_STOP 4
#define MSG_ENABLE 5
#define MSG_HEARTBEAT 6
#define MSG_DIAG 7
// firmware -> host
#define MSG_HELLO_REPLY 8     // body: 17 bytes
#define MSG_TELEMETRY 9       // body: 22 bytes
#define MSG_DIAG_REPLY 10     // body: 31 bytes

#define HELLO_REPLY_SIZE 17
#define TELEMETRY_SIZE 22
#define DIAG_COUNTERS 11
#define DIAG_REPLY_SIZE (9 + 2 * DIAG_COUNTERS)

// status byte
#define STATUS_HOMED 0x01
#define STATUS_WATCHDOG_STOP 0x02
#define STATUS_STOPPED 0x04
#define STATUS_MOVING 0x08
#define STATUS_REJECTED 0x10
#define STATUS_LINK_ERRORS 0x20

// motion (1/16-microstep NEMA17, 200 full steps/rev, 10 mm spool: 101859 steps/m)
#define TICK_HZ 10000UL       // step generator interrupt rate [Hz]
#define MOTION_HZ 1000UL      // velocity/acceleration update rate [Hz]
#define V_MAX_STEPS 2037      // 0.020 m/s [steps/s]
#define ACCEL_STEPS 51000UL   // ~0.5 m/s^2 [steps/s^2]
#define WATCHDOG_MS 25        // host silence that stops the motors [ms]

#endif
