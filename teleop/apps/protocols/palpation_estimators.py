"""The palpation tests' estimators run over a simulated robot's trace (scenes.sim_robot.SimTrace): the FSR
counts -> tension conversion (teleop.core.sensors.FsrConverter) and the per-tick estimate
(teleop.core.estimation.tick.TickComputer) at the commanded poses, each estimator with the same Kalman
noise model; and the traces cut and joined."""

from __future__ import annotations

import numpy as np

from scenes.sim_robot import SimTrace
from teleop.core.estimation.estimators import DynamicParams
from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.tick import TickComputer
from teleop.core.sensors import FsrConverter, default_fsr_calibration

ESTIMATORS = ("non_compensated", "single", "double", "dynamic")


def fsr_tensions(trace, cal=None, deadband_counts: float = 8.0) -> np.ndarray:
    """(n, 6) FSR tensions [N] from a trace's counts (teleop.core.sensors.FsrConverter, branch dead band)."""
    conv = FsrConverter(cal if cal is not None else default_fsr_calibration(), deadband_counts=deadband_counts)
    return np.array([conv.update(c) for c in trace.counts])


def estimate(trace, geom, dt: float, turn=None, names=ESTIMATORS,
             kalman: bool = True, cal=None, progress=None, deadband_counts: float = 8.0, dynamic=None) -> dict:
    """{name: (n, 6) wrench} of each estimator over a SimTrace's counts at its commanded poses.

    The FSR branch dead band (8 counts, about 0.4 N at mid range) matches the sensor's own loading-state
    switch (sensor_hysteresis delta 0.2 N, i.e. 0.4 N of reversal): with the default 3 counts and 1 count
    RMS ADC noise the branch chattered during slow pokes and each flip moved a tension by ~0.9 N (measured).
    """
    conv = FsrConverter(cal if cal is not None else default_fsr_calibration(), deadband_counts=deadband_counts)
    noise = KalmanNoise(dt=dt) if kalman else None
    dyn = dynamic if dynamic is not None else DynamicParams()
    ticks = {n: TickComputer(geom, n, turn=turn if n == "double" else None, kalman=noise, dynamic=dyn)
             for n in names}
    out = {n: np.empty((len(trace.t), 6)) for n in names}
    poses = trace.poses.tolist()
    for k, counts in enumerate(trace.counts):
        t = conv.update(counts).tolist()
        for n, tc in ticks.items():
            out[n][k] = tc.estimate(poses[k], t, dt)[1]
        if progress is not None and k % 1000 == 999:
            progress(1000)
    return out


def concat_traces(traces) -> SimTrace:
    """One SimTrace of `traces` one after the other."""
    return SimTrace(**{k: np.concatenate([getattr(t, k) for t in traces]) for k in SimTrace.__dataclass_fields__})


def slice_trace(trace, a: int, b: int) -> SimTrace:
    """Samples a..b-1 of `trace`."""
    return SimTrace(**{k: getattr(trace, k)[a:b] for k in SimTrace.__dataclass_fields__})
