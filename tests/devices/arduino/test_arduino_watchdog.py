"""Watchdog: the host goes silent -> the firmware stops the steppers within 50 ms of emulated time, in
100 of 100 trials (one emulator, 100 silence episodes, each timed on the emulated clock by the harness)."""

import numpy as np

from devices.arduino.trials import watchdog_trials

from .conftest import HOME_LENGTHS

N_TRIALS = 100
BOUND_MS = 50.0


def test_host_silence_stops_steppers_within_50ms_in_100_of_100_trials(robot, mega):
    result = watchdog_trials(robot, mega, HOME_LENGTHS, n=N_TRIALS, max_attempts=3 * N_TRIALS)
    assert len(result.stop_ms) == N_TRIALS
    assert np.all(result.steps_after_silence > 0)       # every episode was moving when the host fell silent
    assert np.all(result.latched)                        # and the firmware reports the watchdog stop
    assert np.all(result.stop_ms >= 0)
    assert result.stop_ms.max() <= BOUND_MS, f"stop times [ms]: max {result.stop_ms.max():.2f}"
    print(f"\nwatchdog stop [ms, emulated]: max {result.stop_ms.max():.2f} mean {result.stop_ms.mean():.2f} "
          f"min {result.stop_ms.min():.2f}; early trips (host stalls) {result.early_trips}")
