"""Sensors: FSR branch calibration (seed 000 Fig 7), FBG temperature compensation (seed 001), Kp/Kr model."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry
from teleop.core.physics.capstan import tip2motor_transitions
from teleop.core.sensors import (LOADING, UNLOADING, FbgParams, FsrBranchLag, FsrConverter, default_fsr_calibration,
                            default_fsr_calibration_data, eq2_roots, fbg2force, fbg2force_uncompensated,
                            fit_fsr_calibration, fit_proximal_distal, lowpass2, synthesize_fbg,
                            synthesize_fsr_counts)
from teleop.io.calibration_csv import load_fsr_calibration, load_fsr_calibration_csv, write_fsr_calibration_csv

CAL = default_fsr_calibration()


# ----------------------------------------------------------------------------------------------- FSR
def test_default_calibration_has_the_shape_of_seed_fig7():
    d = default_fsr_calibration_data()
    load, unload = d.branch == LOADING, d.branch == UNLOADING
    # 0-600 g in 50 g steps, both ways
    np.testing.assert_allclose(np.sort(d.tension[load]), np.arange(13) * 0.05 * 9.80665)
    np.testing.assert_allclose(np.sort(d.tension[unload]), np.arange(13) * 0.05 * 9.80665)
    gl = d.reading[load][np.argsort(d.tension[load])]
    gu = d.reading[unload][np.argsort(d.tension[unload])]
    assert np.all(np.diff(gl) > 0) and np.all(np.diff(gu) > 0)    # conductance grows with the weight
    assert np.all(gu[1:] > gl[1:])                                  # loading below unloading
    assert gu[-1] != pytest.approx(gl[-1], rel=0.01)                # and they differ at 600 g too


def test_quintic_fits_follow_the_points_and_invert():
    d = default_fsr_calibration_data()
    for b, coefs in ((LOADING, CAL.loading), (UNLOADING, CAL.unloading)):
        assert len(coefs) == 6                                        # quintic
        m = d.branch == b
        resid = CAL.reading(d.tension[m], b) - d.reading[m]
        assert np.abs(resid).max() < 0.02 * d.reading.max()
        a, roots = eq2_roots(coefs)                                   # eq 2 form: a prod(x - x_i)
        x = np.linspace(0.5, 5.8, 7)
        np.testing.assert_allclose(np.real(a * np.prod(x[:, None] - roots[None], axis=1)),
                                   CAL.reading(x, b), rtol=1e-9)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(t=st.floats(0.05, 5.8), branch=st.sampled_from([LOADING, UNLOADING]))
def test_reading_to_tension_inverts_each_branch(t, branch):
    g = CAL.reading(np.array([t]), branch)
    assert CAL.tension(g, branch)[0] == pytest.approx(t, abs=2e-3)
    c = CAL.conductance2counts(g)
    assert CAL.counts2conductance(c)[0] == pytest.approx(g[0], rel=1e-9)


def test_converter_picks_the_branch_from_the_direction_and_ignores_noise():
    rng = np.random.default_rng(0)
    t = np.r_[np.linspace(0.2, 5.0, 400), np.linspace(5.0, 0.5, 400)]
    branch_truth = np.r_[np.full(400, LOADING), np.full(400, UNLOADING)]
    counts = synthesize_fsr_counts(t, branch_truth, CAL, rng=rng, noise_counts=1.0)
    conv = FsrConverter(CAL, n=1, deadband_counts=6.0)  # ~4 sigma of the difference of two samples
    est, branches = [], []
    for c in counts:
        est.append(conv.update([c])[0])
        branches.append(conv.branch[0])
    est, branches = np.array(est), np.array(branches)
    # after the reversal plus the dead band the unloading branch is used, and only one flip happens
    assert np.count_nonzero(np.diff(branches)) == 1
    assert np.all(branches[:400] == LOADING) and np.all(branches[430:] == UNLOADING)
    err = np.abs(est - t)[np.r_[20:400, 430:800]]
    assert np.sqrt(np.mean(err ** 2)) < 0.05
    # using the wrong branch would be off by the hysteresis
    wrong = CAL.tension(CAL.counts2conductance(counts[430:780]), LOADING)
    assert np.sqrt(np.mean((wrong - t[430:780]) ** 2)) > 3 * np.sqrt(np.mean(err ** 2))


def test_branch_lag_reads_each_branch_and_holds_across_the_gap():
    lag = FsrBranchLag(CAL, n=1)
    up = np.linspace(0.2, 5.0, 200)
    down = np.linspace(5.0, 0.5, 200)
    U = lag.run(np.r_[up, down][:, None])[:, 0]
    assert np.allclose(U[:200], up)  # rising: the loading branch
    g = lag.conductance(U)
    tail = np.r_[up, down][-100:]
    assert np.allclose(g[-100:], CAL.reading(tail, UNLOADING), rtol=1e-3)  # falling: the unloading branch
    # right after the turn the reading holds: flat until the tension has crossed the gap at 5 N
    gap5 = float(lag.gap(5.0))
    held = down[down > 5.0 - 0.9 * gap5]
    assert 0.4 < gap5 < 1.0 and np.allclose(U[200:200 + len(held)], 5.0)
    # seed 000 Fig 7: its 600 g unloading point is read one 50 g step back from 650 g: gap < 0.49 N there
    assert float(lag.gap(CAL.t_max)) < 9.80665 * 0.05
    # a step back larger than the gap lands on the unloading branch
    w = np.array([2.0, 4.0, 3.0])
    lag.reset()
    u = lag.run(w[:, None])[-1, 0]
    assert lag.conductance(u) == pytest.approx(CAL.reading(w[-1], UNLOADING), rel=1e-3)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.0, 6.0), min_size=2, max_size=60))
def test_branch_lag_is_monotone_and_step_equals_run(ts):
    """More tension never lowers the reading, on any history; the per-sample and batch forms agree."""
    T = np.array(ts)[:, None]
    a, b = FsrBranchLag(CAL, n=1), FsrBranchLag(CAL, n=1)
    U = a.run(T)
    assert np.allclose(U[:, 0], [b.step(t)[0] for t in T], atol=0)
    dT, dU = np.diff(T[:, 0]), np.diff(U[:, 0])
    assert np.all(dU * dT >= -1e-12)  # the reading never moves against the tension
    assert np.all((U[:, 0] >= T[:, 0] - 1e-12) & (U[:, 0] <= T[:, 0] + a.gap(T[:, 0]) + 1e-12))


def test_fsr_csv_round_trip_and_missing_column(tmp_path):
    d = default_fsr_calibration_data(seed=3)
    path = write_fsr_calibration_csv(tmp_path / "cal.csv", d)
    back = load_fsr_calibration_csv(path)
    np.testing.assert_allclose(back.tension, d.tension, atol=1e-6)
    np.testing.assert_allclose(back.reading, d.reading, atol=1e-12)
    cal = fit_fsr_calibration(back)
    np.testing.assert_allclose(cal.reading(2.0, LOADING), fit_fsr_calibration(d).reading(2.0, LOADING), rtol=1e-4)
    bad = tmp_path / "bad.csv"
    bad.write_text("tension_N,branch\n1.0,loading\n")
    with pytest.raises(InputError, match=r"bad\.csv: missing column 'conductance_uS'") as exc:
        load_fsr_calibration_csv(bad)
    assert "\n" not in str(exc.value)


def test_fsr_csv_bad_values_name_the_row(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("tension_N,conductance_uS,branch\n1.0,abc,loading\n")
    with pytest.raises(InputError, match="row 2"):
        load_fsr_calibration_csv(bad)


# ----------------------------------------------------------------------------------------------- FBG
def test_fbg_temperature_compensation_over_a_24_degree_swing(tmp_path):
    """Seed 001 §3.1.2: 5.38 N weight, 24.21 degC swing. Uncompensated: max error ~18 N; compensated: within
    the sensor's 0.37 N (RMS, and max after the seed's second-order low-pass)."""
    p = FbgParams()
    fs = 10.0
    t = np.arange(0, 600.0, 1 / fs)                   # heat gun: up for 5 min, then cooling
    dT = 24.21 * np.where(t < 300, t / 300, np.exp(-(t - 300) / 120.0))
    F = np.full(t.shape, 5.38)
    dl1, dl2 = synthesize_fbg(F, dT, p, rng=np.random.default_rng(0))
    comp = fbg2force(dl1, dl2, p)
    raw = fbg2force_uncompensated(dl2, p)
    assert np.abs(raw - F).max() > 17.0                # seed: 18.44 N
    err = comp - F
    assert abs(err.mean()) < 0.1                        # seed: 5.44 vs 5.38 N
    assert np.sqrt(np.mean(err ** 2)) <= 1.05 * p.force_error_N
    assert p.force_error_N == pytest.approx(0.37, abs=0.005)
    filt = lowpass2(comp, fs, 0.1)
    assert np.abs(filt - F)[300:].max() < 0.37          # after the filter's 30 s start-up
    # with r away from the sensitivity ratio the temperature leaks back in
    bad = fbg2force(dl1, dl2, FbgParams(r=1.5))
    assert np.abs(lowpass2(bad, fs, 0.1) - F).max() > 5.0
    from teleop.io.outputs import save_figure
    from teleop.core.sensors import plot_fbg_compensation

    png = save_figure(plot_fbg_compensation(t, F, dl1, dl2, dT, p), tmp_path / "fig4c.png")
    assert png.stat().st_size > 10_000


# ------------------------------------------------------------------------------ one sensor for all cables
def _cycles(n, dt, period, amp, offset, phase):
    t = np.arange(n) * dt
    return offset + amp * np.sin(2 * np.pi * t / period + phase)


def test_one_sensor_for_all_identifies_kp_kr_and_estimates_other_cables():
    """Synthetic tendon-sheaths from physics.capstan (stick transitions): each pulls a spring at the tip.
    Cable 1 (instrumented) gives Kp and Kr; cable 2's distal tension is estimated from its proximal one."""
    g = default_geometry()
    mu_theta = g.mu * (g.theta0 + np.deg2rad(400.0))   # a long endoscope route: several bends
    dt, n = 1e-3, 8000
    rng = np.random.default_rng(5)
    runs = []
    for amp, off, per, ph, ks in ((0.02, 0.02, 2.0, 0.0, 400.0), (0.015, 0.03, 1.3, 1.0, 250.0)):
        x = _cycles(n, dt, per, amp, off, ph)            # motor position [m]
        Fd = ks * x                                      # spring at the tip
        Fp = tip2motor_transitions(x, Fd, 1.0, mu_theta, 5e3)
        runs.append((Fp + rng.normal(0, 0.02, n), Fd + rng.normal(0, 0.02, n), Fd))
    (Fp1, Fd1, _), (Fp2, _, Fd2_true) = runs
    model = fit_proximal_distal(Fp1, Fd1)
    assert model.Kp == pytest.approx(np.exp(-mu_theta), rel=0.05)
    assert model.Kr == pytest.approx(np.exp(mu_theta), rel=0.05)
    est = model.distal(Fp2)
    rmse = np.sqrt(np.mean((est - Fd2_true)[500:] ** 2))
    assert rmse < 0.65 / 3                               # seed: 0.65 N on the robot
    # the flat transitions matter: a sign-switch model without them is clearly worse
    dFp = np.gradient(Fp2)
    switch = np.where(dFp > 0, model.Kp * Fp2 + model.bp, model.Kr * Fp2 + model.br)
    assert np.sqrt(np.mean((switch - Fd2_true)[500:] ** 2)) > 2 * rmse


def test_one_sensor_fit_needs_both_phases():
    Fp = np.linspace(1, 5, 100)
    with pytest.raises(InputError, match="pulling and releasing"):
        fit_proximal_distal(Fp, 0.6 * Fp)


def test_converter_float_path_equals_the_array_calibration():
    rng = np.random.default_rng(9)
    counts = rng.integers(-5, 1030, (500, 6)).astype(float)
    counts[5, 2] = np.nan
    conv = FsrConverter(CAL, deadband_counts=2.0)
    for row in counts:
        a = conv.update(row)
        b = CAL.tension(CAL.counts2conductance(row), conv.branch)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_calibration_figure_is_written(tmp_path):
    from teleop.io.outputs import save_figure
    from teleop.core.sensors import plot_fsr_calibration

    path = save_figure(plot_fsr_calibration(default_fsr_calibration_data(), CAL), tmp_path / "fig7.png")
    assert path.stat().st_size > 10_000 and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_tension_noise_matches_the_kalman_noise_model_and_load_helper(tmp_path):
    from teleop.core.estimation.kalman import KalmanNoise
    from teleop.core.sensors import tension_noise

    assert tension_noise(CAL, 1.0, 2.85) == pytest.approx(KalmanNoise().sigma_t, rel=0.25)
    # simulated: the spread of tensions read back from noisy counts
    rng = np.random.default_rng(1)
    counts = synthesize_fsr_counts(np.full(20000, 2.85), LOADING, CAL, rng=rng, noise_counts=1.0)
    back = CAL.tension(CAL.counts2conductance(counts), LOADING)
    assert np.std(back) == pytest.approx(tension_noise(CAL, np.sqrt(1.0 + 1 / 12)), rel=0.15)
    path = write_fsr_calibration_csv(tmp_path / "c.csv", default_fsr_calibration_data())
    assert load_fsr_calibration(path).reading(3.0, LOADING) == pytest.approx(CAL.reading(3.0, LOADING), rel=1e-4)
