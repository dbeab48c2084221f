"""The simulated calibration platform (scenes.fsr_lab) records what seed 000 §2.2 / Fig 7 recorded: 0-600 g on
each branch (650 g the turn, no row), each row the average of the three passes."""

import numpy as np
import pytest

from scenes.fsr_lab import (RECORD_TOP_G, REPEATS, TOP_G, average_passes, calibration_run, plant_fsr_calibration,
                            robot_url_calibration, weight_profile)
from scenes.fsr_sensor import FsrSensorParams
from scenes.sim_robot import SimRobotParams, with_named_plant
from scenes.tendon_sheath import TendonSheathParams
from teleop.core.errors import InputError
from teleop.core.sensors import G, LOADING, UNLOADING, default_fsr_calibration


def test_rows_are_the_seeds_range_each_the_mean_of_the_passes():
    W, holds = weight_profile(REPEATS)
    per = len(holds) // REPEATS
    g = np.arange(len(holds), dtype=float)          # hold i of pass k reads i + k * per
    weight, reading, branch = average_passes(holds, g, REPEATS)
    grams = np.rint(weight / G * 1e3)
    up = np.arange(0.0, RECORD_TOP_G + 1.0, 50.0)
    assert np.array_equal(grams[branch == LOADING], up)                 # 0..600 g, the 650 g turn left out
    assert np.array_equal(grams[branch == UNLOADING], up[::-1])         # 600..0 g
    assert W.max() == pytest.approx(TOP_G * 1e-3 * G)                   # 650 g is reached all the same
    kept = [i for i, h in enumerate(holds[:per]) if h[2] <= RECORD_TOP_G * 1e-3 * G + 1e-9]
    assert np.allclose(reading, np.array(kept) + per * (REPEATS - 1) / 2)  # the passes' mean, not one pass
    # the 600 g unloading row is the hold right after the 650 g one ("decreases from 650 g to 600 g")
    i650 = next(i for i, h in enumerate(holds[:per]) if h[2] > RECORD_TOP_G * 1e-3 * G + 1e-9)
    assert holds[i650 + 1][3] == UNLOADING and np.rint(holds[i650 + 1][2] / G * 1e3) == 600


def test_passes_must_repeat_the_same_holds():
    _, holds = weight_profile(2)
    with pytest.raises(ValueError, match="equal passes"):
        average_passes(holds[:-1], np.zeros(len(holds) - 1), 2)
    shuffled = holds[:len(holds) // 2] + holds[len(holds) // 2:][::-1]
    with pytest.raises(ValueError, match="other weights"):
        average_passes(shuffled, np.zeros(len(holds)), 2)


def test_the_platform_records_26_rows_from_0_to_600_g():
    d = calibration_run(TendonSheathParams(), FsrSensorParams(noise_counts=0.0), 0, repeats=1)
    assert d.tension.size == 26 and np.count_nonzero(d.branch == LOADING) == 13
    assert d.tension.max() == pytest.approx(RECORD_TOP_G * 1e-3 * G)
    # the 600 g unloading row follows 650 g: above the 600 g loading row (friction and the sensor's lag)
    top = d.tension == d.tension.max()
    assert d.reading[top & (d.branch == UNLOADING)][0] > d.reading[top & (d.branch == LOADING)][0]


def test_a_robot_url_names_its_plants_calibration():
    assert robot_url_calibration("sim://robot") is None                       # matched: the built-in serves
    assert robot_url_calibration("sim://robot?plant=rich&seed=2") is None
    assert robot_url_calibration("touch://") is None
    cal = robot_url_calibration("sim://robot?plant=distributed&seed=3&pad=z60")
    assert cal == plant_fsr_calibration(with_named_plant(SimRobotParams(), "distributed", 3))
    assert cal != default_fsr_calibration()
    with pytest.raises(InputError, match="unknown option 'bogus'"):
        robot_url_calibration("sim://robot?plant=distributed&bogus=1")
