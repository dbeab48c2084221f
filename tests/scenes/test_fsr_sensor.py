"""scenes.fsr_sensor: the FSR alone, its datasheet hysteresis as a Preisach (Prandtl-Ishlinskii) operator."""

import numpy as np
import pytest

from scenes.fsr_sensor import INTERLINK_HYSTERESIS, FsrSensor, FsrSensorParams
from teleop.core.errors import InputError
from teleop.core.sensors import LOADING, default_fsr_calibration

CAL = default_fsr_calibration()


def quiet(**kw):
    return FsrSensor(1, 0, FsrSensorParams(noise_counts=0.0, **kw), CAL)


def test_a_full_cycle_opens_the_datasheet_gap():
    # 0 -> 5 N -> 0: at each force the unloading resistance is (1 - 0.10) of the loading one
    up, down = np.linspace(0.2, 5.0, 400), np.linspace(5.0, 0.2, 400)
    lg = quiet().log_conductance(np.r_[up, down][:, None])[:, 0]
    load, unload = np.exp(lg[:400]), np.exp(lg[400:][::-1])
    mid = (up > 0.5) & (up < 3.0)  # away from the top, where the unloading loop is still opening
    R_plus, R_minus = 1 / load[mid], 1 / unload[mid]
    assert np.allclose((R_plus - R_minus) / R_plus, INTERLINK_HYSTERESIS, atol=2e-3)
    # the loading branch is the calibration's loading curve
    assert np.allclose(load, CAL.reading(up, LOADING), rtol=1e-12)


def test_a_partial_reversal_moves_the_reading_by_the_preisach_law():
    # after a reversal of d in ln G (d < 2 gap) the reading moves by d^2 / (4 gap); a single play would not move
    p = FsrSensorParams(noise_counts=0.0, plays=400)
    s = FsrSensor(1, 0, p, CAL)
    top = s.log_conductance(np.linspace(0.5, 2.0, 200)[:, None])[-1, 0]
    x_top = np.log(CAL.reading(2.0, LOADING))
    F_back = 1.8
    d = x_top - np.log(CAL.reading(F_back, LOADING))
    assert 0 < d < 2 * p.gap_log
    moved = top - s.log_conductance(np.array([[F_back]]))[0, 0]
    assert moved == pytest.approx(d ** 2 / (4 * p.gap_log), rel=0.02)


def test_rate_independent_and_stateful():
    path = np.r_[np.linspace(1, 3, 50), np.linspace(3, 1.5, 40), np.linspace(1.5, 2.5, 30)]
    once = quiet().log_conductance(path[:, None])[:, 0]
    slow = quiet().log_conductance(np.repeat(path, 7)[:, None])[::7, 0]   # the same path, 7x the samples
    assert np.allclose(once, slow)
    s = quiet()                                                           # in pieces = in one go
    pieces = np.r_[s.log_conductance(path[:60, None])[:, 0], s.log_conductance(path[60:, None])[:, 0]]
    assert np.array_equal(pieces, once)


def test_noise_is_seeded_and_bad_params_are_refused():
    T = np.full((500, 2), 2.0)
    a, b = FsrSensor(2, 3).run(T), FsrSensor(2, 3).run(T)
    assert np.array_equal(a, b) and not np.array_equal(a, FsrSensor(2, 4).run(T))
    assert 0.7 < np.std(a[:, 0]) < 1.3                                   # 1 count RMS
    with pytest.raises(InputError, match="hysteresis"):
        FsrSensorParams(hysteresis=1.0)
