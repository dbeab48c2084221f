"""Rendering: limits for any input, NaN fault, ramp-in, -z zeroing, frame map, passivity."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devices.base import OMEGA_SPEC, TOUCH_SPEC
from teleop.core.errors import InputError
from teleop.core.rendering import ENGAGED, RAMPING, WAITING, Renderer, RenderParams, clamp_norm, frame_map

wild = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([1e9, -1e9, 1e308, -1e308]))


def engaged(params=RenderParams(ramp_s=0.0)):
    r = Renderer(params)
    r.enable()
    for _ in range(params.engage_ticks + 1):
        r.render(np.zeros(6), 1e-3)
    assert r.state == ENGAGED
    return r


@settings(derandomize=True, max_examples=200, deadline=None)
@given(f=st.lists(wild, min_size=6, max_size=6), v=st.lists(wild, min_size=3, max_size=3),
       spec=st.sampled_from([TOUCH_SPEC, OMEGA_SPEC]), zero_z=st.booleans())
def test_output_is_finite_and_within_the_device_limit_for_any_input(f, v, spec, zero_z):
    r = engaged(RenderParams.for_device(spec, ramp_s=0.0, zero_negative_z=zero_z))
    out = r.render(np.array(f), 1e-3, np.array(v))
    assert np.isfinite(out).all()
    assert np.linalg.norm(out) <= spec.max_force_continuous * (1 + 1e-12)
    if not all(math.isfinite(x) for x in f[:3]) or not all(math.isfinite(x) for x in v):
        assert r.fault and np.all(out == 0.0)


def test_nan_faults_latch_until_reset():
    r = engaged()
    assert np.all(r.render([np.nan, 0, 0, 0, 0, 0], 1e-3) == 0) and r.fault
    assert np.all(r.render([0.1, 0, 0, 0, 0, 0], 1e-3) == 0)         # latched
    r.enable()
    assert np.all(r.render([0.1, 0, 0, 0, 0, 0], 1e-3) == 0)         # enable does not clear a fault
    r.reset()
    assert not r.fault and r.state == "disabled"


def test_ramp_in_engages_only_after_small_force_for_three_ticks():
    p = RenderParams(max_force=3.0, ramp_s=0.01)
    r = Renderer(p)
    big, small = [1.0, 0, 0, 0, 0, 0], [0.1, 0, 0, 0, 0, 0]
    assert np.all(r.render(big, 1e-3) == 0)                          # disabled: zero
    r.enable()
    for _ in range(5):
        assert np.all(r.render(big, 1e-3) == 0) and r.state == WAITING
    assert np.all(r.render(small, 1e-3) == 0)
    assert np.all(r.render(small, 1e-3) == 0)
    assert np.all(r.render(big, 1e-3) == 0)                          # a big one restarts the count
    outs = [r.render(small, 1e-3)[0] for _ in range(3)]
    assert r.state == RAMPING and outs[:2] == [0.0, 0.0] and outs[2] == pytest.approx(0.1 * 0.1)
    ramp = [r.render(big, 1e-3)[0] for _ in range(12)]
    assert np.all(np.diff(ramp) >= 0) and ramp[-1] == pytest.approx(1.0) and r.state == ENGAGED
    assert ramp[0] == pytest.approx(0.2)                             # linear over ramp_s = 10 ticks


def test_clamp_keeps_direction_and_zero_negative_z():
    r = engaged(RenderParams(max_force=0.88, ramp_s=0.0, zero_negative_z=True, alpha_max=0.0))
    out = r.render([3.0, 4.0, -12.0, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(out, [0.88 * 0.6, 0.88 * 0.8, 0.0])
    out = r.render([0.0, 0.0, 0.5, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(out, [0, 0, 0.5])
    assert clamp_norm(1e308, 1e308, 0.0, 1.0) == pytest.approx((math.sqrt(0.5), math.sqrt(0.5), 0.0))
    assert clamp_norm(0.0, 1.0, math.nan, 1.0) == (0.0, 0.0, 0.0)        # a nan that max() would skip
    assert clamp_norm(0.0, math.inf, 0.0, 1.0) == (0.0, 0.0, 0.0)


def test_frame_map_and_scale():
    R = ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))            # 90 deg about z
    assert frame_map(R, 2.0, 1.0, 0.0, 0.5) == (0.0, 2.0, 1.0)
    r = engaged(RenderParams(max_force=5.0, R_dev_B=R, scale=0.5, ramp_s=0.0, alpha_max=0.0))
    np.testing.assert_allclose(r.render([1.0, 0, 0, 0, 0, 0], 1e-3), [0.0, 0.5, 0.0])
    with pytest.raises(InputError, match="rotation"):
        RenderParams(R_dev_B=((1, 0, 0), (0, 2, 0), (0, 0, 1)))


def test_passivity_observer_keeps_the_port_passive():
    """A force that pushes along the motion (an active, energy-generating rendering) gets damped so the
    observed energy stays >= 0 wherever alpha_max allows it; without the guard energy is generated."""
    dt, n = 1e-3, 2000
    t = np.arange(n) * dt
    v = 0.05 * np.cos(2 * np.pi * t)                                  # stylus oscillates along x
    f_active = 0.4 * np.sign(v)                                       # a force that follows the velocity
    energies = {}
    for amax in (0.0, 50.0):
        r = engaged(RenderParams(max_force=0.88, ramp_s=0.0, alpha_max=amax))
        out = np.array([r.render([f, 0, 0, 0, 0, 0], dt, [vk, 0, 0]) for f, vk in zip(f_active, v)])
        energies[amax] = -np.cumsum(out[:, 0] * v * dt)               # energy absorbed from the hand
        assert np.linalg.norm(out, axis=1).max() <= 0.88 + 1e-12
    assert energies[0.0].min() < -0.01                                 # unguarded: the port generates energy
    # guarded: passive up to what alpha_max cannot absorb near the velocity zero crossings
    assert energies[50.0].min() > 0.01 * energies[0.0].min()


def test_negative_z_is_zeroed_in_the_device_frame_with_the_loop_registration():
    """Seed 000 sec 5.2 zeroes -z of the Touch's frame (z toward the user): with the loop's default
    registration the pad's reaction on the tip (-z of {B}) reaches the hand as +z and is kept, while a force
    pulling the tip into the pad (+z of {B}, -z on the device: toward the pad) is removed."""
    from teleop.core.mapping import MappingParams

    R_dev_B = MappingParams().R_reg.T
    r = engaged(RenderParams(max_force=5.0, R_dev_B=R_dev_B, zero_negative_z=True, ramp_s=0.0, alpha_max=0.0))
    reaction = r.render([0.1, 0.2, -0.7, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(reaction, [0.1, -0.2, 0.7])
    pulling = r.render([0.1, 0.2, 0.7, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(pulling, [0.1, -0.2, 0.0])
    assert r.mapped == (0.1, -0.2, 0.0)
    kept = engaged(RenderParams(max_force=5.0, R_dev_B=R_dev_B, ramp_s=0.0, alpha_max=0.0))
    np.testing.assert_allclose(kept.render([0.1, 0.2, 0.7, 0, 0, 0], 1e-3), [0.1, -0.2, -0.7])


@settings(derandomize=True, max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3), st.sampled_from([0.0, 0.05, math.nan])),
                min_size=1, max_size=40))
def test_render_tick_is_render_xyz_and_what_the_loop_reads_after_it(steps):
    """Renderer.render_tick (the loop's one call) = render_xyz, then mapped, ramp (0 while disabled), fault."""
    a, b = Renderer(RenderParams(ramp_s=0.01)), Renderer(RenderParams(ramp_s=0.01))
    for r in (a, b):
        r.enable()
    for fx, fy, fz, v in steps:
        F = a.render_xyz(fx, fy, fz, 1e-3, v, 0.0, -v)
        want = (list(F), a.mapped, a.ramp if a.state != "disabled" else 0.0, a.fault)
        got_F, *rest = b.render_tick(fx, fy, fz, 1e-3, v, 0.0, -v)
        assert type(got_F) is np.ndarray and (list(got_F.tolist()), *rest) == want
        assert a.fault_reason == b.fault_reason
