"""Watchdog: the host goes silent -> the firmware stops the steppers within 50 ms of emulated time, in
100 of 100 trials (one emulator, 100 silence episodes, each timed on the emulated clock by the harness)."""

import numpy as np

from devices.arduino.trials import watchdog_trials

from .conftest import HOME_LENGTHS

N_TRIALS = 100
BOUND_MS = 50.0


def test_host_silence_stops_steppers_within_50ms_in_100_of_100_trials(robot, mega):
    result = watchdog_trials(robot, mega, HOME_LENGTHS, n=N_TRIALS, max_attempts=10 * N_TRIALS)
    assert len(result.stop_ms) == N_TRIALS
    assert np.all(result.steps_after_silence > 0)       # every episode was moving when the host fell silent
    assert np.all(result.latched)                        # and the firmware reports the watchdog stop
    assert np.all(result.stop_ms >= 0)
    assert result.stop_ms.max() <= BOUND_MS, f"stop times [ms]: max {result.stop_ms.max():.2f}"
    print(f"\nwatchdog stop [ms, emulated]: max {result.stop_ms.max():.2f} mean {result.stop_ms.mean():.2f} "
          f"min {result.stop_ms.min():.2f}; early trips (host stalls) {result.early_trips}")


HOST_SCRIPT = """
import sys, time
import numpy as np
from devices.arduino.robot import ArduinoRobot
home = np.full(6, 0.030)
robot = ArduinoRobot(sys.argv[1], timeout_s=1.0)
robot.open()
robot.home(home)
robot.command_lengths(home - 0.02)
t_end = time.monotonic() + 0.08
while time.monotonic() < t_end:
    reading = robot.read()
    time.sleep(0.001)
print("moving" if robot.read_fresh().status & 8 else "idle", flush=True)
time.sleep(60)
"""


def test_killed_host_process_stops_steppers_within_50ms(mega):
    """SIGKILL the host mid-motion (no STOP, port left to the kernel): the firmware watchdog stops."""
    import signal
    import subprocess
    import sys
    import time

    for attempt in range(3):  # a host stall before the kill can trip the watchdog early: try again
        proc = subprocess.Popen([sys.executable, "-c", HOST_SCRIPT, mega.port], stdout=subprocess.PIPE, text=True)
        try:
            line = proc.stdout.readline().strip()
            proc.send_signal(signal.SIGKILL)
        finally:
            proc.wait()
        if line == "moving":
            break
    assert line == "moving", f"the host process never got the motors moving ({line!r})"
    while True:
        time.sleep(0.02)
        status = mega.status()
        if status["t_ns"] - status["last_rx_ns"] >= 70e6:
            break
    stop_ms = (status["last_step_ns"] - status["last_rx_ns"]) * 1e-6
    assert status["steps_after_rx"] > 0 and 0 <= stop_ms <= BOUND_MS
