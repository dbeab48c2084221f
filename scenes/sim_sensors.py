"""Emulated FBG tension sensors of the simulated robot (URL ``sim://robot?sensor=fsr|fbg|one``).

- ``fsr`` (default): the FSR array only (scenes.sim_robot makes its counts; nothing here).
- ``fbg``: every cable carries seed 001's dual-grating FBG sensor on its distal sheath (seed 001 sec. 2.1.2:
  the sensor measures the sheath's compression, equal to the tendon's tension, 3 cm before the sheath's
  end). It reads the tension at the end effector t_tip (the friction of those last 3 cm is left out)
  through the catalogue's sensor_hysteresis (teleop.core.physics.sensor_effects: the loading/unloading offset
  +-h with a play-type switch of half-width delta) and gives the Bragg shifts of eq 2 with the sensor's
  temperature and noise (teleop.core.sensors.synthesize_fbg: dl1 = kT1 dT, dl2 = S F + kT2 dT, the noise split
  between the gratings). The FSR array stays on the robot (its counts are still read).
- ``one``: the FSR array plus that FBG on one cable (`cable`, default 0): seed 001's sensor-model approach.

The sensor temperature warms from the room's (where the shifts were zeroed) toward the body's after the
robot is switched on, each cable's sensor a little differently: T_i(t) = room + (body - room + o_i)
(1 - exp(-t / tau)), o_i uniform in +-spread (seeded). Eq 3 removes it on the estimator's side
(teleop.core.estimation.sensor_reading); FBG2 alone would read kT2 dT / S = 9 N off at 12 degC.

Defaults: seed 001's reported sensor (sec. 3.1), read so that its figures hold together:
- calibration (what the estimator's eq 3 uses): S 34.12 pm/N, r 2.28, kT1 11.23, kT2 25.62 pm/degC
  (teleop.core.sensors.FbgParams).
- hysteresis: 4.798 % of the 20 N calibration span is a 0.96 N loading-unloading gap. The 12.59 pm (0.37 N)
  RMSE is that of one line through the loading and the unloading data, so it holds the hysteresis: an abrupt
  +-0.48 N switch alone would leave 0.48 N RMSE. A play-type switch over half the span (delta = 10 N) with
  h = 0.96 N gives the 0.96 N gap and 0.40 N RMSE about one line over 0-20-0 N (measured with
  teleop.core.physics.hysteresis_offset), i.e. the seed's two figures; small load swings then move the offset
  by h dF / delta (a 1 N swing: 0.1 N).
- temperature: compensated with its own r, the seed's sensor still missed by 0.68 N (low-passed, Fig 4c)
  over 24.21 degC of heating: the sensor's FBG2 follows temperature 0.68 x 34.12 / 24.21 = 0.96 pm/degC
  more steeply than r kT1 (its true ratio 2.37, not the calibrated 2.28); `kT2_error_pm_C`.
- white noise: what the low-pass removed from the max error, 0.94 - 0.68 = 0.26 N, read as ~3.5 sigma of
  white noise: 0.075 N, 2.5 pm on the compensated shift (`noise_pm`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from teleop.core.errors import InputError
from teleop.core.physics import hysteresis_offset
from teleop.core.sensors import FbgParams, check_sensor_kind, synthesize_fbg

#: where the FBG sits: this far before the sheath's distal end [m] (seed 001 sec. 2.1.2)
FBG_FROM_END_M = 0.03


@dataclass(frozen=True)
class FbgEmulation:
    """The emulated FBG sensors (module docstring for the sources).

    Attributes:
        params: the sensor's calibration (what the estimator's eq 3 uses).
        kT2_error_pm_C: the sensor's FBG2 temperature sensitivity minus the calibration's kT2 [pm/degC].
        noise_pm: white noise of the compensated shift dl2 - r dl1 [pm] (synthesize_fbg splits it).
        hysteresis_N: half the loading-unloading gap h [N]; hysteresis_delta_N: the switch half-width [N].
        room_C: temperature at which the shifts were zeroed [degC]; body_C: where the sensors warm to [degC];
        warm_tau_s: time constant of the warming [s]; spread_C: per-sensor spread of the final temperature [degC].
    """

    params: FbgParams = field(default_factory=FbgParams)
    hysteresis_N: float = 0.96
    hysteresis_delta_N: float = 10.0
    kT2_error_pm_C: float = 0.96
    noise_pm: float = 2.5
    room_C: float = 25.0
    body_C: float = 37.0
    warm_tau_s: float = 60.0
    spread_C: float = 1.0

    def __post_init__(self):
        if not (self.hysteresis_N >= 0 and self.hysteresis_delta_N > 0 and self.warm_tau_s > 0
                and self.spread_C >= 0 and self.params.S_pm_N > 0 and self.noise_pm >= 0):
            raise InputError("sim robot FBG: need hysteresis_N >= 0, hysteresis_delta_N > 0, warm_tau_s > 0, "
                             "spread_C >= 0, noise_pm >= 0 and S_pm_N > 0")


def fbg_cables(kind: str, n: int, cable: int = 0) -> list:
    """Indices of the cables that carry an FBG for sensor `kind` (fsr: none, fbg: all, one: [cable])."""
    check_sensor_kind(kind, "sim://robot sensor")
    if kind == "one" and not 0 <= cable < n:
        raise InputError(f"sim://robot: option 'cable' must be a cable index 0..{n - 1}, got {cable}")
    return {"fsr": [], "fbg": list(range(n)), "one": [int(cable)]}[kind]


class FbgArray:
    """The FBG sensors of one simulated robot: tip tensions -> Bragg shifts (2, n) [pm] per reading.

    Row 0 is FBG1 (strain-free: temperature), row 1 FBG2 (force and temperature); NaN on cables without an
    FBG. `read` (one reading) and `run` (many) continue the same state (hysteresis switch, time)."""

    def __init__(self, kind: str, n: int, seed: int, emulation: FbgEmulation = FbgEmulation(), cable: int = 0):
        self.kind = kind
        self.n = n
        self.cables = np.array(fbg_cables(kind, n, cable), dtype=np.int64)
        self.em = emulation
        p = emulation.params  # the sensor as built: its calibration, off by the temperature error, its noise
        self.sensor = replace(p, kT2_pm_C=p.kT2_pm_C + emulation.kT2_error_pm_C, noise_pm=emulation.noise_pm)
        # its own stream: the FSR array's noise draws stay those of a robot without FBGs
        self.rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(0xFB6,)))
        s = emulation.spread_C
        self.offset_C = self.rng.uniform(-s, s, n) if s > 0 else np.zeros(n)
        self.z = None  # hysteresis switch state per instrumented cable [N]

    def temperature(self, t) -> np.ndarray:
        """(m, n) sensor temperatures [degC] at times t (m,) [s]."""
        em = self.em
        t = np.asarray(t, dtype=float).reshape(-1, 1)
        return em.room_C + (em.body_C - em.room_C + self.offset_C) * (1.0 - np.exp(-t / em.warm_tau_s))

    def run(self, T_tip, t) -> np.ndarray:
        """(m, 2, n) Bragg shifts [pm] for tip tensions T_tip (m, n) [N] at times t (m,) [s]."""
        T_tip = np.asarray(T_tip, dtype=float)
        m = T_tip.shape[0]
        out = np.full((m, 2, self.n), np.nan)
        c = self.cables
        if c.size == 0:
            return out
        F = T_tip[:, c]
        em = self.em
        h, d = em.hysteresis_N, em.hysteresis_delta_N
        off = hysteresis_offset(F, h, d, z0=self.z)  # the catalogue's sensor_hysteresis, continued
        self.z = F[-1] - off[-1] * d / h if h > 0 else F[-1].copy()
        sensed = F + off
        dT = self.temperature(t)[:, c] - em.room_C
        dl1, dl2 = synthesize_fbg(sensed, dT, self.sensor, self.rng)
        out[:, 0, c], out[:, 1, c] = dl1, dl2
        return out

    def read(self, t_tip, t: float) -> np.ndarray:
        """(2, n) Bragg shifts [pm] of one reading: tip tensions t_tip (n,) [N] at time t [s]."""
        return self.run(np.asarray(t_tip, dtype=float).reshape(1, -1), [t])[0]
