"""Estimation pipeline: capstan compensation, f = -A t, turn fit, Kalman, estimators, the fast tick."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from teleop.apps.bench.tick import ReferenceTick
from teleop.core.errors import InputError
from teleop.core.estimation.calibrate import fit_dynamic_params, no_load_forces
from teleop.core.direction import DirectionTracker
from teleop.core.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
from teleop.core.estimation.kalman import (FilterpyWrenchKalman, KalmanNoise, SteadyWrenchKalman, _dare_gain,
                                      bandwidth_hz, make_filterpy, wrench_kalman_params)
from teleop.core.estimation.tick import TickComputer
from teleop.core.estimation.turn import AxisTurnFit, TurnCompensation, fit_turn_compensation
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import capstan_angles, poses2lengths, pose2lengths, structure_matrix
from teleop.core.physics.capstan import tip2motor, tip2motor_transitions
from teleop.core.physics.friction import dahl, viscous
from teleop.core.rendering import Renderer, RenderParams
from teleop.core.tension import tensions2wrench, wrench2tensions

G = default_geometry()
PROPS = settings(derandomize=True, max_examples=40, deadline=None)
small = st.floats(-0.004, 0.004)
angle = st.floats(-0.15, 0.15)


def pose_of(x, y, z, b, c):
    return np.array([x, y, z, 0.0, b, c])


# ---------------------------------------------------------------------------------------------- capstan
def tip_tensions(tc: TickComputer, pose, t_fsr, dt=1e-3):
    """(wrench (6,), compensated tip-side tensions (6,)) of one unfiltered tick."""
    out = tc.estimate_into(np.asarray(pose, dtype=float), np.asarray(t_fsr, dtype=float), dt)
    return out[1, :6].copy(), out[2, :6].copy()


@PROPS
@given(x=small, y=small, z=small, b=angle, c=angle, dz=st.floats(-2e-4, 2e-4),
       t_tip=st.lists(st.floats(0.2, 5.5), min_size=6, max_size=6))
def test_single_compensation_inverts_the_capstan_model(x, y, z, b, c, dz, t_tip):
    """Sensor tensions made by physics.capstan.tip2motor with the robot's Theta, each cable pulling while it
    shortens (or holds) and releasing while it lengthens, are mapped back exactly by `single`."""
    q0, q1 = pose_of(x, y, z, b, c), pose_of(x, y, z + dz, b, c)
    pulling = pose2lengths(q1, G) <= pose2lengths(q0, G)
    t_tip = np.array(t_tip)
    t_fsr = tip2motor(t_tip, G.mu, capstan_angles(q1, G), pulling)
    tc = TickComputer(G, "single", kalman=None)
    tc.estimate(q0, t_fsr, 1e-3)
    f, t_back = tip_tensions(tc, q1, t_fsr)
    np.testing.assert_allclose(t_back, t_tip, rtol=1e-12)
    np.testing.assert_allclose(f, tensions2wrench(t_tip, structure_matrix(q1, G)), atol=1e-12)


@PROPS
@given(x=small, y=small, z=small, b=angle, c=angle,
       F=st.lists(st.floats(-1.5, 1.5), min_size=3, max_size=3))
def test_tension_distribution_then_minus_A_t_returns_the_wrench(x, y, z, b, c, F):
    q = pose_of(x, y, z, b, c)
    A = structure_matrix(q, G)
    # a wrench the robot can produce: forces plus the moments they make at the tool tip
    Rr_tip = np.array([0.0, 0.0, 0.025])
    f = np.r_[F, np.cross(Rr_tip, F)]
    f = A @ np.linalg.lstsq(A, f, rcond=None)[0]  # project on the range of A (no moment about the shaft)
    t = wrench2tensions(f, A, G.t_min, G.t_max)
    tc = TickComputer(G, "non_compensated", kalman=None)
    np.testing.assert_allclose(tc.estimate(q, t, 1e-3)[1], f, atol=1e-9)


def test_dynamic_inverts_the_capstan_with_stick_transitions():
    """The friction-state compensation recovers the tip tension through reversals (physics capstan_friction):
    each cable pulls a spring (tip tension follows the motor position), k = 2e4 N/m stick stiffness."""
    n, dt = 3000, 1e-3
    tt = np.arange(n) * dt
    poses = np.zeros((n, 6))
    poses[:, 2] = 0.003 * np.sin(2 * np.pi * tt / 0.8)
    poses[:, 0] = 0.001 * np.sin(2 * np.pi * tt / 1.3)
    L = poses2lengths(poses, G)
    theta = np.array([capstan_angles(q, G) for q in poses])
    x = -(L - L[0])
    t_tip = 2.5 + 300.0 * x
    fsr = np.column_stack([tip2motor_transitions(x[:, i], t_tip[:, i], G.mu, theta[:, i], 2e4) for i in range(6)])
    err = {}
    for name in ("single", "dynamic"):
        tc = TickComputer(G, name, kalman=None, dynamic=DynamicParams(capstan_k=2e4))
        out = np.array([tip_tensions(tc, poses[k], fsr[k], dt)[1] for k in range(n)])
        err[name] = np.abs(out - t_tip)[100:].max()
    # the tip tension moves by 300 N/m x the ~40 um of a transition: 0.012 N, which the physics keeps out of
    # the sticking sensor tension and the friction state lets through (<= 2 x 0.012 N); single jumps
    assert err["dynamic"] < 0.03
    assert err["single"] > 0.3


# --------------------------------------------------------------------------------------------- direction
def test_direction_tracker_dead_band_ignores_noise_and_flags_reversals():
    tr = DirectionTracker(1, deadband=0.1)
    seq = [0.0, 0.05, -0.05, 0.2, 0.5, 0.45, 0.42, 0.3, 0.1, 0.15, 0.25]
    dirs, flips = [], []
    for v in seq:
        dirs.append(int(tr.update([v])[0]))
        flips.append(bool(tr.flipped[0]))
    assert dirs == [0, 0, 0, 1, 1, 1, 1, -1, -1, -1, 1]
    assert flips == [False] * 7 + [True, False, False, True]


# ------------------------------------------------------------------------------------------------ Kalman
def test_kalman_tuning_gives_the_requested_bandwidth_and_filterpy_gain():
    noise = KalmanNoise(dt=1e-3, bandwidth_hz=8.0, sigma_t=0.02)
    kp = wrench_kalman_params(G, noise)
    K = np.array(kp.K[2])
    assert bandwidth_hz(K, noise.dt) == pytest.approx(8.0, rel=0.02)
    # filterpy's converged recursion equals the Riccati fixed point
    np.testing.assert_allclose(K, _dare_gain(noise.dt, kp.q[2] / kp.r[2]), rtol=1e-8)
    # measurement noise is the FSR noise through A: (A diag(s^2) A^T)_kk
    A = structure_matrix(np.zeros(6), G)
    assert kp.r[2] == pytest.approx(((A[2] ** 2).sum()) * 0.02 ** 2)


def test_kalman_covariance_stays_symmetric_positive_definite():
    kp = wrench_kalman_params(G)
    kf = make_filterpy(kp, steady=False)
    rng = np.random.default_rng(3)
    for k in range(400):
        kf.predict()
        kf.update(rng.normal(0.0, 1.0, 6) * (1e3 if k % 97 == 0 else 1.0))
        P = kf.P
        assert np.allclose(P, P.T, atol=1e-12 * np.abs(P).max())
        assert np.linalg.eigvalsh(0.5 * (P + P.T)).min() > 0


def test_steady_state_step_equals_filterpy_recursion():
    kp = wrench_kalman_params(G)
    rng = np.random.default_rng(4)
    z = np.cumsum(rng.normal(0, 0.05, (3000, 6)), axis=0) + rng.normal(0, 0.03, (3000, 6))
    fast, steady, cold = SteadyWrenchKalman(kp), FilterpyWrenchKalman(kp, steady=True), \
        FilterpyWrenchKalman(kp, steady=False)
    a = np.array([fast.update(zk) for zk in z])
    b = np.array([steady.update(zk) for zk in z])
    c = np.array([cold.update(zk) for zk in z])
    np.testing.assert_allclose(a, b, atol=1e-9)          # started at the fixed point: identical
    assert np.abs(a[-500:] - c[-500:]).max() < 1e-9       # started far away: converges to the same
    assert np.abs(a[:5] - c[:5]).max() > 1e-6             # ...and really differed at the start


# -------------------------------------------------------------------------------- plant and comparisons
PLANT = dict(k=2e3, b=5.0, sigma=2e4, Fc=0.05)
DYN = DynamicParams(b=PLANT["b"], dahl_sigma=PLANT["sigma"], dahl_Fc=PLANT["Fc"], capstan_k=PLANT["k"])


def plant(poses, wrench, dt, seed, noise=0.01):
    """FSR tensions from the physics library: tip tensions (tension distribution) -> capstan with stick
    transitions + viscous + Dahl along each cable's motor position, plus sensor noise."""
    rng = np.random.default_rng(seed)
    L = poses2lengths(poses, G)
    theta = np.array([capstan_angles(q, G) for q in poses])
    t_tip = np.array([wrench2tensions(f, structure_matrix(q, G), G.t_min, G.t_max)
                      for q, f in zip(poses, wrench)])
    x = -(L - L[0])
    fsr = np.empty_like(L)
    for i in range(6):
        fsr[:, i] = (tip2motor_transitions(x[:, i], t_tip[:, i], G.mu, theta[:, i], PLANT["k"])
                     + viscous(np.gradient(x[:, i], dt), PLANT["b"]) + dahl(x[:, i], PLANT["sigma"], PLANT["Fc"]))
    return fsr + rng.normal(0.0, noise, fsr.shape)


def tri(t, period):
    return (2 / np.pi) * np.arcsin(np.sin(2 * np.pi * t / period))


def run_fast(name, poses, fsr, dt, turn=None, kalman=None, dyn=DYN):
    tc = TickComputer(G, name, turn=turn, dynamic=dyn, kalman=kalman)
    return np.array([tc.compute(q, t, dt)[1] for q, t in zip(poses.tolist(), fsr.tolist())])


@pytest.fixture(scope="module")
def calibration():
    """The seed's step-3 protocol: no load, back and forth along z (here a cycle at 5 mm/s and one at
    10 mm/s). `double` fits its turn polynomials on it, `dynamic` its friction parameters."""
    dt = 4e-3
    z = np.r_[0.005 * tri(np.arange(0, 4.0, dt), 4.0), 0.005 * tri(np.arange(0, 2.0, dt), 2.0)]
    tt = np.arange(z.size) * dt
    poses = np.zeros((tt.size, 6))
    poses[:, 2] = z
    fsr = plant(poses, np.zeros((tt.size, 6)), dt, seed=1)
    single = run_fast("single", poses, fsr, dt)
    turn = TurnCompensation((fit_turn_compensation(tt, poses, single, axis=2),))
    dyn = fit_dynamic_params(G, poses, fsr, dt)
    return turn, dyn, (tt, poses, fsr, single)


def test_turn_fit_removes_the_jumps_of_the_fitting_run(calibration):
    turn, _, (tt, poses, fsr, single) = calibration
    fit = turn.axes[0]
    assert 0.02 < fit.duration < 1.0
    double = run_fast("double", poses, fsr, tt[1] - tt[0], turn=turn)
    jump = lambda w: np.abs(w[:, 2] - np.median(w[:, 2])).max()  # noqa: E731
    assert jump(double) < 0.5 * jump(single)


def test_dynamic_fit_zeroes_the_no_load_run(calibration):
    _, dyn, (tt, poses, fsr, single) = calibration
    f = no_load_forces(G, poses, fsr, tt[1] - tt[0], dyn)
    assert np.sqrt(np.mean(f ** 2)) < 0.2 * np.sqrt(np.mean(single[:, :3] ** 2))
    assert dyn.b == pytest.approx(PLANT["b"], rel=0.5) and dyn.dahl_Fc == pytest.approx(PLANT["Fc"], rel=0.5)


def test_turn_fit_needs_turns_both_ways():
    tt = np.arange(0, 1.0, 1e-3)
    poses = np.zeros((tt.size, 6))
    poses[:, 2] = 0.001 * tt
    with pytest.raises(InputError, match="turns both ways"):
        fit_turn_compensation(tt, poses, np.zeros((tt.size, 6)))


def test_dynamic_beats_double_on_a_variable_speed_run_with_reversals(calibration):
    """Both calibrated on the same no-load run; evaluated on a loaded run at varying speed."""
    turn, dyn, _ = calibration
    dt = 2e-3
    tt = np.arange(0, 6.0, dt)
    phase = 2 * np.pi * (tt / 3.0 + 0.15 * np.sin(2 * np.pi * tt / 2.3) + 0.1 * np.sin(2 * np.pi * tt / 0.9))
    poses = np.zeros((tt.size, 6))
    poses[:, 2] = 0.004 * np.sin(phase)
    poses[:, 0] = 0.001 * np.sin(2 * np.pi * tt / 4.1)
    truth = np.zeros((tt.size, 6))
    truth[:, 2] = -1.0 * np.clip(poses[:, 2] / 0.004, 0.0, None)  # a pad pushing back while z > 0
    fsr = plant(poses, truth, dt, seed=2)
    rmse = {}
    for name in ESTIMATOR_NAMES:
        w = run_fast(name, poses, fsr, dt, turn=turn, kalman=KalmanNoise(dt=dt), dyn=dyn)
        rmse[name] = float(np.sqrt(np.mean((w[:, :3] - truth[:, :3]) ** 2)))
    assert rmse["dynamic"] < 0.4 * rmse["double"], rmse
    assert rmse["dynamic"] < 0.4 * rmse["single"], rmse
    assert rmse["dynamic"] < 0.15, rmse


# ------------------------------------------------------------- the tick == the reference tick == its source
def equal_runs(name, turn, source=False):
    """Largest difference between TickComputer and bench's ReferenceTick (numpy, scipy Rotation, filterpy)
    over a run through reversals, turns and orientation changes; source=True runs the kernel's Python
    source (`py_func`, what runs without numba) instead of the compiled kernel."""
    rng = np.random.default_rng(7)
    n, dt = 400, 1e-3
    tt = np.arange(n) * dt
    poses = np.zeros((n, 6))
    poses[:, 2] = 0.004 * np.sin(2 * np.pi * tt / 0.19)
    poses[:, 0] = 0.002 * np.sin(2 * np.pi * tt / 0.15)
    poses[:, 4] = 0.1 * np.sin(3 * tt)
    poses[:, 5] = 0.05 * np.cos(2 * tt)
    T = 2.5 + rng.normal(0, 0.3, (n, 6))
    vel = rng.normal(0, 0.05, (n, 3))
    dyn = DynamicParams(b=5.0, dahl_sigma=2e4, dahl_Fc=0.05, v_smooth=0.005)
    rp = RenderParams(max_force=3.0, ramp_s=0.05, engage_N=20.0)
    fast = TickComputer(G, name, turn=turn, dynamic=dyn, renderer=Renderer(rp))
    if source:
        fast.kernel = fast.kernel.py_func
    ref = ReferenceTick(G, name, turn=turn, dynamic=dyn, renderer=Renderer(rp))
    for r in (fast.renderer, ref.renderer):
        r.enable()
    worst = 0.0
    for k in range(n):
        L2, w2, F2 = fast.compute(poses[k], T[k], dt, vel[k])
        L3, w3, F3 = ref.compute(poses[k], T[k], dt, vel[k])
        worst = max(worst, np.abs(L3 - L2).max(), np.abs(w3 - w2).max(), np.abs(F3 - np.array(F2)).max())
    return worst, fast


@pytest.mark.parametrize("name", ESTIMATOR_NAMES)
def test_tick_equals_the_reference_tick(name):
    rng = np.random.default_rng(8)
    poly = tuple(tuple(rng.normal(0, 0.1, 5)) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.3, forward=poly, backward=poly[::-1]),
                             AxisTurnFit(axis=0, duration=0.2, forward=poly[::-1], backward=poly)))
    worst, fast = equal_runs(name, turn)
    assert worst < 1e-9
    assert fast.renderer.state == "engaged"


@pytest.mark.parametrize("name", ["single", "dynamic"])
def test_the_kernel_source_runs_as_python_with_the_same_numbers(name):
    """Without numba the kernels' own source runs (no second copy): same numbers as the reference."""
    poly = tuple((0.05, -0.1, 0.05) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.3, forward=poly, backward=poly),))
    worst, _ = equal_runs(name, turn, source=True)
    assert worst < 1e-9


def test_tick_computer_rejects_bad_names_and_nan_faults_the_renderer():
    with pytest.raises(InputError, match="unknown estimator"):
        TickComputer(G, "magic")
    with pytest.raises(InputError, match="turn compensation"):
        TickComputer(G, "double")
    tc = TickComputer(G, "dynamic")
    tc.renderer.enable()
    _, _, F = tc.compute(np.zeros(6), [np.nan] + [2.0] * 5, 1e-3)
    assert F == (0.0, 0.0, 0.0) and tc.renderer.fault
    tc.reset()
    assert not tc.renderer.fault


def test_reading_estimator_follows_the_loop_protocol_and_round_trips_its_description():
    import json

    from devices.base import RobotReading
    from teleop.core.estimation.reading import ReadingEstimator
    from teleop.core.sensors import LOADING, default_fsr_calibration, synthesize_fsr_counts

    cal = default_fsr_calibration()
    poly = tuple((0.01, -0.02, 0.0) for _ in range(6))
    turn = TurnCompensation((AxisTurnFit(axis=2, duration=0.2, forward=poly, backward=poly),))
    est = ReadingEstimator(G, "double", cal=cal, turn=turn)
    desc = json.loads(json.dumps(est.describe()))
    again = ReadingEstimator.rebuild(desc, G)
    assert again.describe() == desc
    rng = np.random.default_rng(0)
    for k in range(200):
        q = np.array([0.0, 0.0, 0.003 * np.sin(k / 20), 0.0, 0.0, 0.0])
        counts = synthesize_fsr_counts(np.full(6, 2.85), LOADING, cal, rng=rng, noise_counts=1.0)
        r = RobotReading(t=k * 1e-3, seq=k, fsr_counts=counts, position_steps=np.zeros(6),
                         commanded_lengths=pose2lengths(q, G))
        t1, f1 = est.update(r, q, 1e-3)
        t2, f2 = again.update(r, q, 1e-3)
        assert t1.shape == (6,) and f1.shape == (6,) and np.isfinite(f1).all()
        np.testing.assert_array_equal(f1, f2)
    assert np.abs(t1 - 2.85).max() < 0.3


def test_reading_estimator_tensions_equal_the_fsr_converter():
    """The loop's float FSR path (branch trigger, per-count table) against teleop.core.sensors.FsrConverter."""
    from teleop.core.estimation.reading import ReadingEstimator
    from teleop.core.sensors import LOADING, FsrConverter, default_fsr_calibration, synthesize_fsr_counts

    cal = default_fsr_calibration()
    est = ReadingEstimator(G, "dynamic", cal=cal, deadband_counts=4.0)
    conv = FsrConverter(cal, deadband_counts=4.0)
    rng = np.random.default_rng(5)
    tt = np.arange(600) * 1e-3
    tension = 3.0 + 2.5 * np.sin(2 * np.pi * 3.0 * tt[:, None] + np.arange(6))  # rises and falls per cable
    flips = 0
    for k in range(tt.size):
        counts = synthesize_fsr_counts(tension[k], LOADING, cal, rng=rng, noise_counts=2.0)
        counts = counts.astype(float)
        if k % 37 == 0:  # out of the ADC range (clipped), its ends, and between two counts
            counts[k % 6] = [-3.0, 2000.0, -1.0, 0.0, 1023.0, 1e9, 511.5][k // 37 % 7]
        fast = est.tensions(counts.tolist())
        np.testing.assert_array_equal(fast, conv.update(counts))
        flips += int(conv.tracker.flipped.sum())
    assert flips > 20
