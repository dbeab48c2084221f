"""The distributed tendon-sheath cable (scenes.tendon_sheath) against its closed-form limits: the capstan
ratio in steady sliding, Kaneko's dead zone and apparent stiffness over a uniform bend, the frictionless
spring, no energy created over a cycle, convergence in N, and one source for the step and the batch."""

import dataclasses
import math

import numpy as np
import pytest

from scenes import sim_robot_kernels
from scenes import tendon_sheath_kernels as K
from scenes.tendon_sheath import TOML_KEYS, SheathLoad, TendonSheath, TendonSheathParams, apparent_stiffness, \
    b_node, capstan_ratio, dead_zone_uniform, span_weights, tension_at_b
from teleop.core.errors import InputError
from teleop.core.kernels import jit

EA = 1.0e4  # [N]
K_LOAD = 1.0e3  # [N/m]
PRETENSION = 3.0  # [N]


def uniform(mu=0.2, Theta=math.pi, **kw) -> TendonSheathParams:
    """A sheath bent uniformly over its whole length (1 m) by Theta [rad], Coulomb mu (no Stribeck peak)."""
    base = dict(EA=EA, mu_c=mu, mu_s=mu, theta0=0.0, theta1=Theta, route_span=(0.0, 1.0), scaffold_span=(1.0, 1.0))
    return TendonSheathParams(**{**base, **kw})


def ramp(x0, x1, speed=1e-3, tick=1e-3) -> np.ndarray:
    """Motor travel from x0 to x1 [m] at `speed` [m/s], one value a tick (x0 excluded)."""
    n = max(1, round(abs(x1 - x0) / speed / tick))
    return np.linspace(x0, x1, n + 1)[1:]


def sine_drive(params, seconds=4.0, tick=1e-3, amplitude=1e-3, hz=0.5):
    """The robot's kind of drive: motor sine (amplitude [m], hz), the kinematic bend swinging +-0.4 rad."""
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=2.85, tick=tick)
    t = np.arange(round(seconds / tick)) * tick
    run = sheath.run(amplitude * np.sin(2 * math.pi * hz * t), theta=0.4 * np.sin(2 * math.pi * hz / 2 * t),
                     keep_tensions=True)
    return sheath, run


# ---- steady sliding: the capstan law -----------------------------------------------------------------------

@pytest.mark.parametrize("case", ["uniform", "robot"])
def test_steady_sliding_gives_the_capstan_ratio_pulling_and_releasing(case):
    if case == "uniform":
        params, theta = uniform(mu_s=0.3, v_s=1e-4), 0.0  # a Stribeck peak, gone at 10 v_s
    else:  # the default sheath: route, scaffold and kinematic bends at their places, mu_s = 1.2 mu_c
        params, theta = TendonSheathParams(), 0.5
    Theta = params.theta0 + params.theta1 + theta
    mu = params.mu_c
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=PRETENSION)
    pull = sheath.run(ramp(0.0, 2e-3), theta=theta)
    ratio = pull.f_motor[-1, 0] / pull.f_tip[-1, 0]
    assert ratio == pytest.approx(capstan_ratio(mu * Theta), rel=0.01)
    release = sheath.run(ramp(2e-3, -1e-3), theta=theta)
    ratio = release.f_motor[-1, 0] / release.f_tip[-1, 0]
    assert ratio == pytest.approx(1 / capstan_ratio(mu * Theta), rel=0.01)
    assert pull.f_tip[-1, 0] > PRETENSION > release.f_tip[-1, 0]  # the load moved both ways


def test_capstan_ratio_holds_at_any_tension_the_profile_is_exponential():
    params = uniform()
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=PRETENSION)
    sheath.run(ramp(0.0, 2e-3))
    T = sheath.tensions[0]  # element tensions, motor to tip
    s = (np.arange(params.n_elements) + 0.5) * params.element_length
    slope = np.polyfit(s, np.log(T), 1)[0]  # T(s) = T_tip exp(mu kappa (L - s))
    assert slope == pytest.approx(-params.mu_c * params.theta1 / params.length, rel=0.01)


# ---- the dead zone and apparent stiffness after a reversal (Kaneko) ----------------------------------------

@pytest.mark.parametrize("mu, Theta", [(0.2, math.pi), (0.1, 2 * math.pi)])
def test_dead_zone_after_a_reversal_matches_the_uniform_bend_closed_form(mu, Theta):
    params = uniform(mu, Theta, sigma0=mu / 1e-6)  # 1 um of pre-sliding: near Coulomb's law
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=PRETENSION)
    x_rev = 2e-3
    pull = sheath.run(ramp(0.0, x_rev))
    down = ramp(x_rev, 0.0)
    release = sheath.run(down)
    t_tip = pull.f_tip[-1, 0]
    D = dead_zone_uniform(t_tip, EA, params.length, mu * Theta)
    travel = x_rev - down
    F = release.f_tip[:, 0]
    # inside the dead zone the tip holds its force
    assert np.max(np.abs(F[travel < 0.8 * D] - t_tip)) < 0.01 * (t_tip - F[-1])
    # past it the tip force falls along a line: the release's apparent stiffness in series with the load;
    # the line meets the reversal's force at the dead zone's end
    late = (travel > 1.5 * D) & (travel < 1.5 * D + 5e-4)
    slope, icpt = np.polyfit(travel[late], F[late], 1)
    k_series = 1 / (1 / apparent_stiffness(EA, params.length, mu * Theta, pulling=False) + 1 / K_LOAD)
    assert -slope == pytest.approx(k_series, rel=0.01)
    assert (icpt - t_tip) / -slope == pytest.approx(D, rel=0.02)


def test_pulling_apparent_stiffness_matches_the_closed_form():
    mu, Theta = 0.2, math.pi
    params = uniform(mu, Theta)
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=PRETENSION)
    x = ramp(0.0, 2e-3)
    F = sheath.run(x).f_tip[:, 0]
    late = x > 1e-3
    slope = np.polyfit(x[late], F[late], 1)[0]
    assert slope == pytest.approx(1 / (1 / apparent_stiffness(EA, params.length, mu * Theta) + 1 / K_LOAD),
                                  rel=0.01)


# ---- no friction: a pure spring ----------------------------------------------------------------------------

def smooth(amplitude=1e-3, seconds=3.0, hz=0.5, tick=1e-3) -> np.ndarray:
    """Motor travel amplitude (1 - cos(2 pi hz t)) [m]: starts at rest and never jumps in speed (the cable's own
    mass, accelerated, adds m a to the force: ~4e-4 N in a tick from rest to 1 mm/s)."""
    t = np.arange(1, round(seconds / tick) + 1) * tick
    return amplitude * (1 - np.cos(2 * math.pi * hz * t))


def test_frictionless_sheath_is_a_spring_EA_over_L_in_series_with_the_load():
    params = uniform(0.0)
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=PRETENSION)
    x = smooth(1.5e-3)  # hauls in 3 mm, releases, hauls in again
    run = sheath.run(x)
    k_series = 1 / (params.length / EA + 1 / K_LOAD)
    assert np.allclose(run.f_tip[:, 0], PRETENSION + k_series * x, rtol=0, atol=1e-5)
    assert np.allclose(run.f_motor[:, 0], run.f_tip[:, 0], rtol=0, atol=1e-5)


def test_frictionless_sheath_under_a_force_and_under_a_held_tip():
    params = uniform(0.0)
    force = TendonSheath(params, SheathLoad("force"), pretension=PRETENSION)
    F = PRETENSION + np.linspace(0.0, 2.0, 200)
    run = force.run(np.zeros(200), tip_input=F)  # the motor holds, the load grows: the cable stretches
    assert np.allclose(run.x_tip[:, 0], -(F - PRETENSION) * params.length / EA, rtol=0, atol=5e-8)
    held = TendonSheath(params, SheathLoad("position"), pretension=PRETENSION)
    x = smooth()
    tip = 0.25 * x
    run = held.run(x, tip_input=tip)
    assert np.allclose(run.x_tip[:, 0], tip, rtol=0, atol=1e-12)
    assert np.allclose(run.f_tip[:, 0], PRETENSION + EA / params.length * (x - tip), rtol=0, atol=1e-5)
    assert np.allclose(run.f_motor[:, 0], run.f_tip[:, 0], rtol=0, atol=1e-5)


def test_a_held_tip_reacts_the_cable_s_tension_less_the_sheath_friction():
    params = uniform(sigma0=0.2 / 1e-6)  # near Coulomb: the nodes by the tip move less than the default's 36 um
    held = TendonSheath(params, SheathLoad("position"), pretension=PRETENSION)
    run = held.run(ramp(0.0, 1e-3), tip_input=0.0)
    ratio = run.f_motor[-1, 0] / run.f_tip[-1, 0]
    # every node slides but the held tip node, whose half element's bend carries no friction
    mu_Theta = params.mu_c * params.theta1
    assert capstan_ratio(mu_Theta * (1 - 1 / params.n_elements)) < ratio < capstan_ratio(mu_Theta)
    assert np.all(run.x_tip == 0.0)


def test_the_tip_input_is_held_when_none_is_given():
    sheath = TendonSheath(uniform(), SheathLoad("force"), pretension=PRETENSION)
    sheath.step(0.0, PRETENSION + 1.0)
    assert np.array_equal(sheath.held_tip_input(), [PRETENSION + 1.0])
    a = sheath.run(np.zeros(50))
    assert np.all(a.f_tip == PRETENSION + 1.0)


# ---- energy ------------------------------------------------------------------------------------------------

def cycle_dissipation(params) -> np.ndarray:
    """Energy dissipated [J] in each 2 s cycle of the sine drive: motor work - work on the load - the change
    of the cable's elastic energy sum T^2 / 2k."""
    sheath, run = sine_drive(params, seconds=6.0)
    k = params.element_stiffness
    E = np.sum(run.tensions[:, 0, :] ** 2, axis=1) / (2 * k)
    out = []
    for c in range(3):
        sl = slice(c * 2000, (c + 1) * 2000)
        fm, xm, ft, xt = run.f_motor[sl, 0], run.x_motor[sl, 0], run.f_tip[sl, 0], run.x_tip[sl, 0]
        w_motor = np.sum(0.5 * (fm[1:] + fm[:-1]) * np.diff(xm))
        w_tip = np.sum(0.5 * (ft[1:] + ft[:-1]) * np.diff(xt))
        out.append(w_motor - w_tip - (E[sl.stop - 1] - E[sl.start]))
    return np.array(out)


def test_energy_dissipated_per_cycle_is_positive_and_zero_without_friction():
    lossy = cycle_dissipation(TendonSheathParams())
    assert np.all(lossy > 0)
    lossless = cycle_dissipation(TendonSheathParams(mu_c=0.0, mu_s=0.0))
    assert np.all(np.abs(lossless) < 1e-3 * lossy.min())


def test_energy_dissipated_with_bristle_damping_and_viscous_friction():
    params = TendonSheathParams(sigma1=0.01, sigma2=0.5)
    assert np.all(cycle_dissipation(params) > cycle_dissipation(TendonSheathParams()).min() * 0.5)


# ---- discretization ----------------------------------------------------------------------------------------

def test_doubling_N_changes_the_outputs_by_less_than_one_percent():
    _, a = sine_drive(TendonSheathParams(n_elements=20))
    _, b = sine_drive(TendonSheathParams(n_elements=40))
    for name in ("f_motor", "f_tip", "x_tip"):
        A, B = getattr(a, name)[:, 0], getattr(b, name)[:, 0]
        assert np.max(np.abs(A - B)) < 0.01 * np.ptp(A), name
    # and the friction shows: the motor's force loop is wider than the tip's
    assert np.ptp(a.f_motor) > 1.5 * np.ptp(a.f_tip)


def test_four_kilohertz_ticks_agree_with_one_kilohertz():
    _, a = sine_drive(TendonSheathParams(), tick=1e-3)
    _, b = sine_drive(TendonSheathParams(), tick=2.5e-4)
    # the 4 kHz run's every fourth tick had the same motor input
    assert np.max(np.abs(a.f_motor[:, 0] - b.f_motor[::4, 0])) < 0.01 * np.ptp(a.f_motor)
    assert np.max(np.abs(a.f_tip[:, 0] - b.f_tip[::4, 0])) < 0.01 * np.ptp(a.f_tip)


# ---- one source: the step and the batch --------------------------------------------------------------------

def test_the_step_and_the_batch_give_the_same_output():
    params = TendonSheathParams()
    rng = np.random.default_rng(7)
    m, c = 400, 3
    x = np.cumsum(rng.normal(0, 2e-5, (m, c)), axis=0)
    theta = 0.3 * np.sin(np.linspace(0, 3, m))[:, None] + np.zeros(c)
    f = 2.85 + np.cumsum(rng.normal(0, 0.01, (m, c)), axis=0)
    batch = TendonSheath(params, SheathLoad("force"), pretension=2.85, n_cables=c)
    first = batch.run(x[:150], tip_input=f[:150], theta=theta[:150])
    second = batch.run(x[150:], tip_input=f[150:], theta=theta[150:])
    stepped = TendonSheath(params, SheathLoad("force"), pretension=2.85, n_cables=c)
    rows = np.array([stepped.step(x[k], f[k], theta[k]) for k in range(m)])
    for i, name in enumerate(("f_motor", "f_tip", "x_tip")):
        assert np.array_equal(np.vstack([getattr(first, name), getattr(second, name)]), rows[:, :, i]), name
    assert np.array_equal(batch.tensions, stepped.tensions)


def test_cables_are_independent():
    params = TendonSheathParams()
    x = np.stack([ramp(0.0, 1e-3), -ramp(0.0, 1e-3)], axis=1)
    two = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=2.0, n_cables=2).run(x, theta=np.array([[0.2, 0.0]]))
    one = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=2.0).run(x[:, 1])
    assert np.array_equal(two.f_tip[:, 1], one.f_tip[:, 0])
    assert not np.allclose(two.f_tip[:, 0], two.f_tip[:, 1])


@pytest.mark.parametrize("kind, tip, n", [("force", 2.85, 4), ("position", 0.0, 5)])
def test_a_cable_s_numbers_do_not_depend_on_when_the_others_converge(kind, tip, n):
    """The cables share each compiled step (their Newton sweeps interleaved a group at a time: 4 and 5 cables
    leave a short last group); one that needs more Newton iterations (a reversal, slack) must not change
    another's numbers, in either mode of the tip node."""
    params = TendonSheathParams()
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.normal(0, 3e-5, (300, n)), axis=0)
    x[:, 2] = 2e-3 * np.sin(np.linspace(0, 12, 300))  # reversals and slack on cable 2 only
    alln = TendonSheath(params, SheathLoad(kind), pretension=2.85, n_cables=n).run(x, tip)
    assert np.ptp(alln.iterations[:, 2]) > 0 and not np.array_equal(alln.iterations[:, 2], alln.iterations[:, 0])
    for c in range(n):
        one = TendonSheath(params, SheathLoad(kind), pretension=2.85).run(x[:, c], tip)
        for name in ("f_motor", "f_tip", "x_tip", "iterations"):
            assert np.array_equal(getattr(alln, name)[:, c], getattr(one, name)[:, 0]), (c, name)


def test_taps_report_their_elements_tensions_every_tick():
    params = TendonSheathParams()
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=2.0, n_cables=2, taps=(3, 17))
    x = np.stack([ramp(0.0, 1e-3), ramp(0.0, 5e-4, speed=5e-4)], axis=1)
    run = sheath.run(x, theta=0.3, keep_tensions=True)
    assert np.array_equal(run.tapped[:, 0], run.tensions[:, :, 3]) and np.array_equal(run.tapped[:, 1],
                                                                                        run.tensions[:, :, 17])
    out = np.empty((sheath.out_rows, 2))
    sheath.step_into(np.full(2, 1.1e-3), np.zeros(2), np.full(2, 0.3), out)
    assert sheath.out_rows == 6 and np.array_equal(out[4:], sheath.tensions[:, [3, 17]].T)
    with pytest.raises(InputError, match="taps"):
        TendonSheath(params, taps=(20,))


def test_node_taps_read_the_tension_at_b_as_tension_at_b_does():
    """A node tap (the robot's FSR at B) reads each tick what tension_at_b reads from that tick's element
    tensions, between the node's two elements' (not the distal element's own)."""
    params = TendonSheathParams()
    j = b_node(params)
    sheath = TendonSheath(params, SheathLoad("spring", K_LOAD), pretension=2.0, n_cables=2, taps=(3,),
                          node_taps=(j, 0))
    x = np.stack([ramp(0.0, 1e-3), ramp(0.0, 5e-4, speed=5e-4)], axis=1)
    run = sheath.run(x, theta=0.3, keep_tensions=True)
    assert sheath.out_rows == 7 and np.array_equal(run.tapped[:, 0], run.tensions[:, :, 3])
    for c in range(2):
        assert np.array_equal(run.tapped[:, 1, c], tension_at_b(run.tensions[:, c], params))
    assert np.array_equal(run.tapped[:, 2], run.tensions[:, :, 0])  # node 0: the first element's
    T = run.tensions[-1]
    assert np.all((T[:, j - 1] - run.tapped[-1, 1]) * (T[:, j] - run.tapped[-1, 1]) < 0)  # strictly between
    with pytest.raises(InputError, match="node_taps"):
        TendonSheath(params, node_taps=(20,))


def test_tension_at_b_without_bends_and_when_slack():
    p = dataclasses.replace(TendonSheathParams(), theta0=0.0, theta1=0.0)
    T = np.array([[3.0] * 16 + [2.0] * 4, [3.0] * 16 + [0.0] * 4])
    assert np.array_equal(tension_at_b(T, p), [2.0, 0.0])  # no bend at B: the distal element's
    assert np.array_equal(tension_at_b(T, TendonSheathParams()), [2.0 * 1.5 ** (140 / 3 / (140 / 3 + 22.5)), 0.0])


@pytest.mark.skipif(not jit.COMPILED, reason="numba not installed (or TELEOP_NO_JIT)")
def test_the_cable_kernels_caches_carry_every_kernel_source_s_stamp():
    """The robot's reading kernel holds the cable's step and the core reading kernels compiled in: its cache
    and the cable's go stale with any of their sources (jit.OUTER_KERNELS), as the core kernels' do."""
    for k in (K.step, K.run, sim_robot_kernels.reading_cables):
        assert k._cache._cache_file._source_stamp == jit._kernels_stamp()
    names = [name for name, _ in jit._kernel_files()]
    assert "scenes/tendon_sheath_kernels.py" in names and "scenes/sim_robot_kernels.py" in names


def test_the_input_map_gives_the_plain_sheath_s_numbers():
    """motor_ref, motor_sign, theta_offset: the robot's cable lengths L and capstan wraps drive the cable as its
    haul-in L_home - L and kinematic bend wrap - theta0 would."""
    params = TendonSheathParams()
    rng = np.random.default_rng(5)
    L_home, theta0 = np.array([0.025, 0.03]), 2.4
    L = L_home + np.cumsum(rng.normal(0, 2e-5, (200, 2)), axis=0)
    wrap = theta0 + 0.3 * np.sin(np.linspace(0, 3, 200))[:, None] + np.zeros(2)
    mapped = TendonSheath(params, pretension=2.85, n_cables=2, motor_ref=L_home, motor_sign=-1.0, theta_offset=theta0)
    plain = TendonSheath(params, pretension=2.85, n_cables=2)
    a = mapped.run(L, 2.85, wrap)
    b = plain.run(L_home - L, 2.85, wrap - theta0)
    for name in ("x_motor", "f_motor", "f_tip", "x_tip"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


# ---- parameters --------------------------------------------------------------------------------------------

def test_bend_weights_put_each_bend_where_its_span_is():
    params = TendonSheathParams(n_elements=20)
    W = params.bend_weights
    assert np.allclose(W.sum(axis=1), 1.0)
    s = (np.arange(20) + 0.5) * params.element_length
    assert np.allclose(W[0][(s < 0.8) | (s > 0.95)], 0, atol=1e-12) and np.allclose(W[2][s < 0.95], 0, atol=1e-12)
    assert np.all(W[0][(s > 0.8) & (s < 0.95)] > 0.3)
    assert np.allclose(span_weights((0.25, 0.25), 1.0, 20), np.eye(20)[5])


def test_from_dict_and_toml_take_edge_units_and_refuse_unknown_keys(tmp_path):
    assert {f for f, _ in TOML_KEYS.values()} == {f.name for f in dataclasses.fields(TendonSheathParams)}
    p = TendonSheathParams.from_dict({"theta0_deg": 90, "EA_N": 1.2e4, "n_elements": 30,
                                      "kinematic_span_m": [0.9, 1.0]})
    assert p.theta0 == pytest.approx(math.pi / 2) and p.EA == 1.2e4 and p.n_elements == 30
    assert p.kinematic_span == (0.9, 1.0)
    with pytest.raises(InputError, match="unknown key"):
        TendonSheathParams.from_dict({"theta0": 1.0})
    with pytest.raises(InputError, match="n_elements"):
        TendonSheathParams.from_dict({"n_elements": 10})
    f = tmp_path / "cable.toml"
    f.write_text("[tendon_sheath]\nmu_c = 0.08\nmu_s = 0.1\nroute_span_m = [0.0, 0.5]\n")
    q = TendonSheathParams.from_toml(f)
    assert (q.mu_c, q.mu_s, q.route_span) == (0.08, 0.1, (0.0, 0.5))
    with pytest.raises(InputError, match="no \\[cable\\]"):
        TendonSheathParams.from_toml(f, table="cable")


@pytest.mark.parametrize("bad", [dict(n_elements=19), dict(EA=0.0), dict(mu_s=0.01), dict(route_span=(0.5, 2.0)),
                                 dict(sigma0=-1.0)])
def test_bad_parameters_are_refused(bad):
    with pytest.raises(InputError):
        TendonSheathParams(**bad)


def test_loads_check_their_settings():
    with pytest.raises(InputError):
        SheathLoad("spring")
    with pytest.raises(InputError):
        SheathLoad("force", stiffness=1.0)
    with pytest.raises(InputError):
        SheathLoad("rope")
