"""The diagnosis's own noise estimate is within 20 % of the truth (issue 26 d3), on data with known noise: a
residual whose misfit sits at reversals and drifts slowly (what a first-difference estimate took for noise),
and the final residual of diagnosed effect-free recordings the diagnosis did not make."""

import numpy as np
import pytest

from teleop.core.physics.links import predict
from teleop.diagnosis.diagnose import diagnose, noise_estimate
from teleop.io.recording_io import read_interchange
from tests.diagnosis._independent import Case, make, write_csv


@pytest.mark.parametrize("sigma", [0.003, 0.018, 0.3])
def test_white_noise_under_misfit_spikes_and_drift(sigma):
    rng = np.random.default_rng(1)
    n = 20000
    t = np.arange(n) / 1000.0
    r = rng.normal(0.0, sigma, n) + 5 * sigma * np.sin(0.3 * t)      # slow structure
    r[::1000] += 200 * sigma            # a switch a sample late at each reversal: the band, two samples long
    r[1::1000] += 200 * sigma
    r[500::1000] -= 200 * sigma
    assert noise_estimate(r) == pytest.approx(sigma, rel=0.2)
    # the estimate it replaces (first differences, at least half their standard deviation) read them as noise
    old = max(1.4826 * np.median(np.abs(np.diff(r))) / np.sqrt(2), np.std(np.diff(r)) / np.sqrt(2) * 0.5)
    assert old > 2 * sigma


def test_a_constant_residual_has_no_noise():
    assert noise_estimate(np.zeros(100)) == 0.0


@pytest.mark.parametrize("case", [Case(ratio=1.5, noise_frac=0.002, seconds=10.0, freq=1.0, seed=2),
                                  Case(ratio=4.0, tip=False, noise_frac=0.02, seconds=10.0, freq=1.0, seed=3)],
                         ids=["tip sensor, 0.2 %", "spring law, 2 %"])
def test_diagnosed_recordings_noise_within_20_percent(tmp_path, case):
    made = make(case)
    diag = diagnose(read_interchange(write_csv(made, tmp_path / "rec.csv")))
    force = next(res for res in diag.links if res.data.link.kind == "force")
    r = force.data.y - predict(force.data, force.final.model)
    assert noise_estimate(r) == pytest.approx(made.noise_N, rel=0.2)
