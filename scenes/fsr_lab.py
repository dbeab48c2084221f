"""The FSR calibration a lab would fit on the simulated plant: seed 000's calibration platform run in simulation.

Seed 000 §2.2 (Fig 6, Fig 7): "The cable, threading through the robot scaffold, is connected to a weight via a
pulley. The cable tension is assumed to be equal to the weight. [...] The loading and unloading process was
repeated three times". Here that platform is one cable of the distributed plant (scenes.sim_robot
DistributedCables, the plant's own cable): the motor holds, the weight hangs on the cable's end (a force load,
the C-D bend straight: wrap theta0 only), and the robot's FSR at B (scenes.fsr_sensor.FsrSensor, the sensor
alone) is read:

    weights 0, 50, ..., 650 g up, 600, ..., 0 g down (seed 000 Fig 7's range, the step of
    teleop.core.calibration.generate.fsr_step_protocol), `REPEATS` times; each weight put on over RAMP_S and
    held HOLD_S; the reading is the mean conductance over the hold's second half (counts through the divider)

and the rows (weight [N], conductance [uS], branch) are fitted by `teleop calibrate fsr`'s fit
(teleop.core.calibration.fsr.fit_fsr: a polynomial of degree <= 5 per branch). The calibration so holds the
sensor's own hysteresis and whatever the plant's cable puts between the weight and B (its friction when the
weight's step moves the cable), as the seed's did with its rig's; nothing in it is taken from the figures it
is checked against. The sensor's true loading curve is the built-in calibration's loading branch
(teleop.core.sensors.default_fsr_calibration), as in FsrSensor.

`plant_fsr_calibration(sim, seed)`: the calibration the estimators of a simulated robot with SimRobotParams
`sim` use: this lab calibration when its FSRs are the sensor alone (`sim.fsr` set, the distributed plant),
else the built-in one (whose branch gap is the robot's FsrBranchLag). One lab calibrates once: the platform's
ADC noise is seeded by LAB_SEED whatever the run's seed; computed once per (cable, sensor) in a process.

`python -m scenes.fsr_lab F.csv` writes the platform's rows (default cable and FSR) for
`teleop calibrate fsr F.csv --out cal.toml`, whose file `teleop session --fsr-calibration` takes (a session on
`sim://robot?plant=distributed` converts with the built-in calibration otherwise).
"""

from __future__ import annotations

import functools

import numpy as np

from scenes.fsr_sensor import FsrSensor, FsrSensorParams
from scenes.sim_robot import DistributedCables
from scenes.tendon_sheath import TendonSheathParams
from teleop.core.calibration.fsr import FsrFit, fit_fsr
from teleop.core.sensors import G, LOADING, UNLOADING, FsrCalibration, FsrCalibrationData, default_fsr_calibration
from teleop.io.calibration_csv import write_fsr_calibration_csv

STEP_G, TOP_G = 50.0, 650.0    # [g] the weights' step and the heaviest (seed 000 Fig 7's range)
REPEATS = 3                    # loading and unloading passes (seed 000 §2.2)
RAMP_S, HOLD_S = 0.2, 1.0      # [s] putting a weight on, holding it
LAB_SEED = 0                   # the platform's noise seed (one calibration, whatever the run's seed)
TICK_S = 1e-3                  # [s] the plant's tick on the platform
THETA0 = np.deg2rad(140.0)     # [rad] the scaffold bend B-C (seed 000 Fig 8; the robot's geometry theta0)


def weight_profile(repeats: int = REPEATS) -> tuple[np.ndarray, list]:
    """(hanging weight [N] per tick (m,), holds [(first tick of the averaged half, end tick, weight [N],
    branch)]): the step protocol of the module docstring."""
    up = np.arange(0.0, TOP_G + 0.5 * STEP_G, STEP_G)
    down = up[-2::-1]
    ramp, hold = int(round(RAMP_S / TICK_S)), int(round(HOLD_S / TICK_S))
    W, holds, prev = [], [], 0.0
    for _ in range(repeats):
        for grams, branch in [(g, LOADING) for g in up] + [(g, UNLOADING) for g in down]:
            w = grams * 1e-3 * G
            W.append(np.linspace(prev, w, ramp + 1)[1:])
            W.append(np.full(hold, w))
            end = sum(len(a) for a in W)
            holds.append((end - hold // 2, end, w, branch))
            prev = w
    return np.concatenate(W), holds


def calibration_run(cable: TendonSheathParams, sensor: FsrSensorParams, seed: int,
                    repeats: int = REPEATS) -> FsrCalibrationData:
    """The platform's rows (tension = the weight [N], conductance [S] the FSR at B reads, branch) on `cable`
    with the FSR `sensor` (its noise seeded by `seed`)."""
    W, holds = weight_profile(repeats)
    m = len(W)
    truth = default_fsr_calibration()
    cables = DistributedCables(cable, 1, float(W[0]) if W[0] > 0 else 0.0, TICK_S, 0.0, float(THETA0))
    t_b = cables.run(np.zeros((m, 1)), W[:, None], np.full((m, 1), THETA0))[0]
    counts = FsrSensor(1, seed, sensor, truth).run(t_b).astype(float)[:, 0]
    g = np.array([truth.counts2conductance(np.mean(counts[a:b])) for a, b, _, _ in holds], dtype=float)
    return FsrCalibrationData(np.array([h[2] for h in holds]), g, np.array([h[3] for h in holds]),
                              source=f"scenes.fsr_lab.calibration_run (simulated seed 000 Fig 6 platform, seed {seed})")


@functools.lru_cache(maxsize=8)
def lab_fit(cable: TendonSheathParams, sensor: FsrSensorParams, seed: int) -> FsrFit:
    """`teleop calibrate fsr`'s fit of `calibration_run` (once per arguments in a process)."""
    return fit_fsr(calibration_run(cable, sensor, seed))


def plant_fsr_calibration(sim, seed: int = LAB_SEED) -> FsrCalibration:
    """The FSR calibration the estimators of a robot with SimRobotParams `sim` use (module docstring)."""
    if getattr(sim, "fsr", None) is None or sim.cable is None:
        return default_fsr_calibration()
    return lab_fit(sim.cable, sim.fsr, int(seed)).cal


if __name__ == "__main__":  # pragma: no cover - `python -m scenes.fsr_lab CSV` (module docstring)
    import sys  # the command line of this module only

    if len(sys.argv) != 2:
        sys.exit("usage: python -m scenes.fsr_lab CSV  (the default distributed cable and FSR, LAB_SEED)")
    print(write_fsr_calibration_csv(sys.argv[1], calibration_run(TendonSheathParams(), FsrSensorParams(), LAB_SEED)))
