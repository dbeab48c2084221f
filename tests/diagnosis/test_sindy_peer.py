"""The PySINDy peer (teleop.diagnosis.sindy_peer) picks its model on a validation part carved from the fit
part, never on the held-out part, and guards extrapolation: an input that drifts past the fit part's range
(a warm-up) ruins a plain degree-3 fit but not the peer; a lag is caught by the free-run form; the choice is
reported."""

import warnings

import numpy as np
import pysindy as ps
import pytest

from teleop.core.physics.links import Link, LinkData
from teleop.diagnosis.diagnose import split
from teleop.diagnosis.sindy_peer import DEGREES, THRESHOLDS, sindy_rmse

FS = 100.0      # [Hz]
SIGMA = 0.05    # output noise [N]


def _drifting(seed: int) -> LinkData:
    """y = 2 u + noise [N] on a force link whose temperature warms steadily (1.5 degC/s), so the held-out
    part's temperature lies beyond anything the fit part saw; the output does not depend on it."""
    rng = np.random.default_rng(seed)
    t = np.arange(1000) / FS
    u = np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 1.9 * t + 1.0)
    temp = 20.0 + 1.5 * t + rng.normal(0, 0.02, t.size)
    y = 2.0 * u + rng.normal(0, SIGMA, t.size)
    return LinkData(Link("force", "motor_force", "tip_force"), t, u, y, None, None, temp, None)


def _plain_cubic_rmse(d: LinkData, fit: slice, hold: slice) -> float:
    """Held-out RMSE of the fit a user would try first: degree 3 + Fourier on the standardised inputs, no
    threshold, no validation, no guard (pysindy alone)."""
    W = np.column_stack([d.u, d.temperature])
    Z = (W - W[fit].mean(0)) / W[fit].std(0)
    lib = ps.PolynomialLibrary(degree=3) + ps.FourierLibrary(n_frequencies=1)
    lib.fit(Z[fit])
    T = np.asarray(lib.transform(Z))
    opt = ps.STLSQ(threshold=0.0, alpha=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        opt.fit(T[fit], d.y[fit, None])
    r = (T @ opt.coef_[0] - d.y)[hold]
    return float(np.sqrt(np.mean(r * r)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_drifting_input_ruins_the_plain_fit_not_the_validated_peer(seed):
    d = _drifting(seed)
    fit, hold = split(d.n, 0.4)
    assert _plain_cubic_rmse(d, fit, hold) > 5 * SIGMA          # the trap is real
    r = sindy_rmse(d, fit, hold)
    assert r["static"] < 1.3 * SIGMA
    assert r["best"] == min(r["static"], r["free_run"])
    c = r["choice"]["static"]
    assert c["degree"] in DEGREES and c["threshold"] in THRESHOLDS and c["guard"] in ("none", "clip", "linear")
    assert c["terms"] >= 1 and c["validation_rmse"] < 1.3 * SIGMA
    # a cubic kept only with a guard: unguarded, it is the plain fit above
    assert c["degree"] == 1 or c["guard"] != "none"


def test_the_choice_never_looks_at_the_held_out_part():
    d = _drifting(4)
    fit, hold = split(d.n, 0.4)
    a = sindy_rmse(d, fit, hold)
    y = d.y.copy()
    y[hold] += 10.0 * np.sin(7.0 * d.t[hold])     # a held-out part nothing could predict
    b = sindy_rmse(LinkData(d.link, d.t, d.u, y, None, None, d.temperature, None), fit, hold)
    assert a["choice"] == b["choice"]
    assert b["static"] > 5 * a["static"]


def test_the_free_run_form_catches_a_lag_the_static_form_cannot():
    rng = np.random.default_rng(3)
    t = np.arange(4000) / FS
    u = np.sin(2 * np.pi * 0.4 * t) + 0.6 * np.sin(2 * np.pi * 1.3 * t + 2.0)
    tau, sigma = 0.25, 0.01       # [s], [m]
    y = np.zeros(t.size)
    for k in range(1, t.size):
        y[k] = y[k - 1] + (u[k - 1] - y[k - 1]) / (FS * tau)
    d = LinkData(Link("position", "tip_pos", "motor_pos"), t, u, y + rng.normal(0, sigma, t.size),
                 None, None, None, None)
    fit, hold = split(d.n, 0.4)
    r = sindy_rmse(d, fit, hold)
    assert r["free_run"] < 1.5 * sigma < 10 * sigma < r["static"]
    assert r["best"] == r["free_run"]
    c = r["choice"]["free_run"]
    assert c["form"] in ("discrete", "continuous") and c["guard"] == "clip" and c["degree"] in DEGREES
