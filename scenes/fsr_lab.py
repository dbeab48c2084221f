"""The FSR calibration a lab would fit on the simulated plant: seed 000's calibration platform run in simulation.

Seed 000 §2.2 (Fig 6, Fig 7): "The cable, threading through the robot scaffold, is connected to a weight via a
pulley. The cable tension is assumed to be equal to the weight. [...] The loading and unloading process was
repeated three times". Here that platform is one cable of the distributed plant (scenes.sim_robot
DistributedCables, the plant's own cable): the motor holds, the weight hangs on the cable's end (a force load,
the C-D bend straight: wrap theta0 only), and the robot's FSR at B (scenes.fsr_sensor.FsrSensor, the sensor
alone) is read:

    weights 0, 50, ..., 650 g up, 600, ..., 0 g down (the step of
    teleop.core.calibration.generate.fsr_step_protocol), `REPEATS` times; each weight put on over RAMP_S and
    held HOLD_S; the reading is the mean conductance over the hold's second half (counts through the divider)

and the rows are what the seed recorded: seed 000 Fig 7's 0-600 g on each branch ("from 0 to 600 g and from
600 to 0 g"; 650 g is the turn, "the unloading 5.89 N reading is acquired when the weight decreases from 650 g
(6.38 N) to 600 g", so the 650 g hold gives no row, RECORD_TOP_G), each row the average of the REPEATS passes
at that weight and branch ("repeated three times and the average values were recorded", `average_passes`).
The rows (weight [N], conductance [uS], branch) are fitted by `teleop calibrate fsr`'s fit
(teleop.core.calibration.fsr.fit_fsr: a polynomial of degree <= 5 per branch, conductance in weight as the
seed's eq 2 P(x)). The calibration so holds the
sensor's own hysteresis and whatever the plant's cable puts between the weight and B (its friction when the
weight's step moves the cable), as the seed's did with its rig's; nothing in it is taken from the figures it
is checked against. The sensor's true loading curve is the built-in calibration's loading branch
(teleop.core.sensors.default_fsr_calibration), as in FsrSensor.

`plant_fsr_calibration(sim, seed)`: the calibration the estimators of a simulated robot with SimRobotParams
`sim` use: this lab calibration when its FSRs are the sensor alone (`sim.fsr` set, the distributed plant),
else the built-in one (whose branch gap is the robot's FsrBranchLag). One lab calibrates once: the platform's
ADC noise is seeded by LAB_SEED whatever the run's seed; computed once per (cable, sensor) in a process.

`robot_url_calibration(url)`: the same for a device URL (`teleop session` and `teleop bench sim` on
`sim://robot?plant=distributed` convert with it unless `--fsr-calibration` names a file).
`python -m scenes.fsr_lab F.csv` writes the platform's rows (default cable and FSR) for
`teleop calibrate fsr F.csv --out cal.toml`, whose file `teleop session --fsr-calibration` takes.
"""

from __future__ import annotations

import functools
from urllib.parse import parse_qs, urlparse

import numpy as np

from scenes.fsr_sensor import FsrSensor, FsrSensorParams
from scenes.sim_robot import DistributedCables, from_url
from scenes.tendon_sheath import TendonSheathParams
from teleop.core.calibration.fsr import FsrFit, fit_fsr
from teleop.core.kernels.sensor import counts2conductance
from teleop.core.sensors import G, LOADING, UNLOADING, FsrCalibration, FsrCalibrationData, default_fsr_calibration
from teleop.io.calibration_csv import write_fsr_calibration_csv

STEP_G, TOP_G = 50.0, 650.0    # [g] the weights' step and the heaviest, the turn (seed 000 §2.2, Fig 7's text)
RECORD_TOP_G = 600.0           # [g] the heaviest recorded row (seed 000 Fig 7: 0-600 g, the FSR's 600 g capacity)
REPEATS = 3                    # loading and unloading passes, averaged (seed 000 §2.2)
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


def average_passes(holds: list, g: np.ndarray, repeats: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(weight [N], reading, branch) per recorded row: the readings g (len(holds),) of `weight_profile`'s holds
    averaged over its `repeats` passes (each pass the same holds in the same order), the holds heavier than
    RECORD_TOP_G (the turn) left out; rows in a pass's order."""
    per = len(holds) // repeats
    if per * repeats != len(holds) or per == 0:
        raise ValueError(f"{len(holds)} holds are not {repeats} equal passes")
    first = holds[:per]
    for k in range(1, repeats):
        if [(h[2], h[3]) for h in holds[k * per:(k + 1) * per]] != [(h[2], h[3]) for h in first]:
            raise ValueError(f"pass {k + 1} holds other weights than pass 1")
    mean = np.asarray(g, dtype=float).reshape(repeats, per).mean(axis=0)
    keep = np.array([h[2] <= RECORD_TOP_G * 1e-3 * G * (1 + 1e-12) for h in first])
    return (np.array([h[2] for h in first])[keep], mean[keep], np.array([h[3] for h in first], dtype=float)[keep])


def calibration_run(cable: TendonSheathParams, sensor: FsrSensorParams, seed: int,
                    repeats: int = REPEATS) -> FsrCalibrationData:
    """The platform's recorded rows (tension = the weight [N], conductance [S] the FSR at B reads, averaged over
    the passes, branch) on `cable` with the FSR `sensor` (its noise seeded by `seed`; module docstring)."""
    W, holds = weight_profile(repeats)
    m = len(W)
    truth = default_fsr_calibration()
    cables = DistributedCables(cable, 1, float(W[0]) if W[0] > 0 else 0.0, TICK_S, 0.0, float(THETA0))
    t_b = cables.run(np.zeros((m, 1)), W[:, None], np.full((m, 1), THETA0))[0]
    counts = FsrSensor(1, seed, sensor, truth).run(t_b).astype(float)[:, 0]
    # the scalar kernel the loop's converter uses (compiled by the warm-up: no new compilation in a session)
    g = np.array([counts2conductance(float(np.mean(counts[a:b])), float(truth.r_divider), float(truth.adc_max))
                  for a, b, _, _ in holds], dtype=float)
    weight, reading, branch = average_passes(holds, g, repeats)
    return FsrCalibrationData(weight, reading, branch,
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


def robot_url_calibration(url: str) -> FsrCalibration | None:
    """The FSR calibration the estimators of the robot a device URL names convert with when it is not the
    built-in one: for `sim://robot?...&plant=distributed[&cable_params=F]` (its FSRs the sensor alone) this
    plant's platform calibration (`plant_fsr_calibration`, the one palpation, the blind rig and `teleop bench
    seed` use); None for any other URL or plant (the built-in calibration serves). The URL's options are
    checked as when the robot is built (scenes.sim_robot.from_url: a bad one is an InputError)."""
    u = urlparse(url)
    if (u.scheme, u.netloc) != ("sim", "robot"):
        return None
    params = from_url(u, {k: v[-1] for k, v in parse_qs(u.query).items()}).params
    return None if params.fsr is None or params.cable is None else plant_fsr_calibration(params)


if __name__ == "__main__":  # pragma: no cover - `python -m scenes.fsr_lab CSV` (module docstring)
    import sys  # the command line of this module only

    if len(sys.argv) != 2:
        sys.exit("usage: python -m scenes.fsr_lab CSV  (the default distributed cable and FSR, LAB_SEED)")
    print(write_fsr_calibration_csv(sys.argv[1], calibration_run(TendonSheathParams(), FsrSensorParams(), LAB_SEED)))
