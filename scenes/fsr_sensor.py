"""The FSR as a sensor alone: its own hysteresis, separate from the friction of the rig it was calibrated on.

`teleop.core.sensors.FsrBranchLag` makes the simulated FSR hold its reading until the tension has crossed the
calibration's whole branch gap. That gap was measured with the cable running through the scaffold to a
pulley-hung weight (seed 000 §2.2, Fig 6: "hysteresis is observed due to friction in the tendon-sheath
mechanism"), so it holds the calibration cable's friction as well as the sensor's. `FsrSensor` is the sensor
alone, the plant side of the FSR chain:

    tension F [N] -> the calibration's loading branch G_L(F) [S] -> the sensor's hysteresis on ln G
    -> voltage divider -> 10-bit ADC + seeded Gaussian noise [counts]

**Hysteresis.** The size: Interlink Electronics, FSR 400 Series Data Sheet (PDS-10004-C), "Hysteresis +10 %
average (R_F+ - R_F-)/R_F+", R_F+ the resistance at a force reached by increasing force, R_F- by decreasing it,
measured at 1000 g. So on a full unloading the sensor's conductance lies 1 / (1 - 0.10) above its loading
value at the same force: a gap of gap_log = -ln(1 - 0.10) = 0.105 in ln G. Seed 000's sensor (RP-C5LT-LF5) is
the same construction (a thin-film piezoresistive polymer FSR) with no hysteresis figure of its own; we take
Interlink's (our assumption). The shape: the Preisach operator that Paredes-Madrid et al. (2018,
"Experimental characterization, modeling and compensation of hysteresis in force sensing resistors", DYNA
85(205) 191-198) fit to FSR loading/unloading cycles, here in its simplest form: a Prandtl-Ishlinskii sum of
`plays` play operators on x = ln G_L(F) of equal weight, the widths spread evenly over (0, 2 gap_log], so
that a full reversal opens the datasheet's gap (their mean width) and a partial one a smaller loop:

    y_i = clip(y_i, x, x + w_i),  ln G = mean_i y_i        (rate-independent, no time constant)

After a reversal of size d < 2 gap_log in x the reading lags by d - d^2 / (4 gap_log) and has moved by
d^2 / (4 gap_log): it never holds a whole swing the way a single play (the calibration's gap as one
threshold) does. The state starts on the loading branch (y_i = x at the first reading).

Noise: the ADC's 1 count RMS (seeded; `teleop.core.sensors` uses the same figure for the robot's FSRs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scenes.fsr_sensor_kernels import counts_rows, log_conductance_rows
from teleop.core.errors import InputError
from teleop.core.sensors import FsrCalibration, default_fsr_calibration

#: Interlink FSR 400 Series Data Sheet: hysteresis (R_F+ - R_F-)/R_F+ = +10 % average (at 1000 g)
INTERLINK_HYSTERESIS = 0.10


@dataclass(frozen=True)
class FsrSensorParams:
    """The FSR alone (module docstring for the sources).

    Attributes:
        hysteresis: (R_F+ - R_F-) / R_F+ of a full loading-unloading cycle [-] (Interlink: 0.10).
        plays: play operators of the Prandtl-Ishlinskii sum [-] (more: a smoother partial loop).
        noise_counts: ADC noise RMS [counts].
    """

    hysteresis: float = INTERLINK_HYSTERESIS
    plays: int = 16
    noise_counts: float = 1.0

    def __post_init__(self):
        if not (0.0 <= self.hysteresis < 1.0 and int(self.plays) >= 1 and self.noise_counts >= 0):
            raise InputError("FSR sensor: need 0 <= hysteresis < 1, plays >= 1 and noise_counts >= 0, got "
                             f"{self.hysteresis!r}, {self.plays!r}, {self.noise_counts!r}")

    @property
    def gap_log(self) -> float:
        """The full cycle's gap in ln G [-]: -ln(1 - hysteresis)."""
        return -float(np.log1p(-self.hysteresis))

    def widths(self) -> np.ndarray:
        """(plays,) play widths in ln G [-], evenly over (0, 2 gap_log]: their mean is gap_log."""
        k = int(self.plays)
        return 2.0 * self.gap_log * (np.arange(1, k + 1) - 0.5) / k


class FsrSensor:
    """n FSRs, each with its own hysteresis state and the one seeded noise stream.

    `run` takes (m, n) tensions [N] and returns (m, n) ADC counts (int64), continuing the state; `log_conductance`
    is the hysteresis alone (no divider, no noise); `counts_into` the counts with a caller's noise (the simulated
    robot's ADC stream). All three step the same state through the kernels of scenes.fsr_sensor_kernels."""

    def __init__(self, n: int = 1, seed: int = 0, params: FsrSensorParams = FsrSensorParams(),
                 cal: FsrCalibration | None = None):
        self.n = int(n)
        self.params = params
        self.cal = default_fsr_calibration() if cal is None else cal
        self.rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(0xF5A,)))
        self._w = np.ascontiguousarray(params.widths())  # (plays,)
        self._c = np.asarray(self.cal.loading, dtype=float)  # the loading branch's coefficients
        self.y = np.empty((self._w.shape[0], self.n))  # (plays, n) play outputs [ln S] (set at the first reading)
        self._fresh = np.ones(1, dtype=np.bool_)  # [True] while nothing was read (a kernel may clear it in place)

    def reset(self) -> None:
        self._fresh[0] = True

    def _state(self) -> bool:
        """True if nothing was read yet (and from now on False)."""
        first = bool(self._fresh[0])
        self._fresh[0] = False
        return first

    def kernel_args(self) -> tuple:
        """(loading coefficients, plays y, widths, fresh flag (1,) bool, r_divider, adc_max): the state (written
        in place) and constants for a compiled caller of fsr_sensor_kernels.counts_row (scenes.sim_robot_kernels),
        which sets the plays at the first reading when fresh[0] and then clears it, as these methods do."""
        return self._c, self.y, self._w, self._fresh, float(self.cal.r_divider), float(self.cal.adc_max)

    def log_conductance(self, T) -> np.ndarray:
        """(m, n) ln G [ln S] the sensors read for tensions T (m, n) [N]: the loading branch, then the plays."""
        T = np.ascontiguousarray(np.asarray(T, dtype=float).reshape(-1, self.n))
        out = np.empty(T.shape)
        first = self._state()
        log_conductance_rows(T, self._c, self.y, self._w, first, out)
        return out

    def counts_into(self, T, noise, counts) -> None:
        """counts (m, n) int64 (written) for tensions T (m, n) [N] and ADC noise (m, n) [counts], C-contiguous
        float arrays: the divider and the 10-bit ADC of the calibration after `log_conductance`."""
        first = self._state()
        counts_rows(T, self._c, self.y, self._w, first, float(self.cal.r_divider), float(self.cal.adc_max), noise,
                    counts)

    def run(self, T) -> np.ndarray:
        """(m, n) int64 ADC counts for tensions T (m, n) [N] (a 1-D T is one cable's series when n = 1)."""
        T = np.asarray(T, dtype=float)
        rows = np.ascontiguousarray(T.reshape(-1, self.n))
        noise = (self.rng.normal(0.0, self.params.noise_counts, rows.shape) if self.params.noise_counts > 0
                 else np.zeros(rows.shape))
        counts = np.empty(rows.shape, dtype=np.int64)
        self.counts_into(rows, noise, counts)  # the one compiled chain: plays, divider, ADC
        return counts.reshape(T.shape)
