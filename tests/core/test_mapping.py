"""teleop.core.mapping: scale, registration, workspace clamp, length limits, the per-tick step limit, and the float
Follower the loop runs against the numpy functions."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import pose2lengths, rotation_zyx
from teleop.core.mapping import (Follower, MappingParams, is_aligned, limit_lengths, platform_offsets, position2lengths,
                            stylus2target)

G = default_geometry()
vec = st.lists(st.floats(-0.2, 0.2), min_size=3, max_size=3).map(np.array)


def test_incremental_scaled_mapping_with_registration():
    m = MappingParams(motion_scale=0.25)
    p = stylus2target(np.array([0.004, 0.004, -0.008]), np.zeros(3), np.zeros(3), m)
    assert np.allclose(p, [0.001, -0.001, 0.002])  # stylus down (-z) pokes the robot forward (+z)


@settings(max_examples=80)
@given(vec, vec)
def test_target_always_inside_workspace(p, anchor):
    m = MappingParams()
    q = stylus2target(p, anchor, np.zeros(3), m)
    assert np.all(q >= m.workspace_min) and np.all(q <= m.workspace_max)


@settings(max_examples=60)
@given(st.lists(st.floats(-0.005, 0.005), min_size=3, max_size=3), st.floats(-0.3, 0.3), st.floats(-0.3, 0.3))
def test_position2lengths_matches_kinematics(p, b, g):
    q = np.array([*p, 0.0, b, g])
    assert np.allclose(position2lengths(q[:3], platform_offsets(G, q[3:])), pose2lengths(q, G), atol=1e-15)


@settings(max_examples=100)
@given(st.lists(st.floats(-1.0, 1.0, allow_nan=False), min_size=6, max_size=6),
       st.lists(st.floats(0.005, 0.06), min_size=6, max_size=6), st.floats(1e-4, 1e-2))
def test_limit_lengths_bounds_and_step(target, prev, dt):
    L = limit_lengths(np.array(target), np.array(prev), G, dt)
    assert np.all(L >= G.l_min) and np.all(L <= G.l_max)
    assert np.max(np.abs(L - np.array(prev))) <= G.v_max * dt * (1 + 1e-12)


def test_alignment():
    m = MappingParams(align_tol=np.deg2rad(20))
    assert is_aligned(np.eye(3), m) and is_aligned(rotation_zyx(1.0, 0.2, 0.1), m)
    assert not is_aligned(rotation_zyx(0.0, 0.5, 0.0), m) and not is_aligned(np.full((3, 3), np.nan), m)


def test_bad_params():
    with pytest.raises(InputError):
        MappingParams(motion_scale=0)
    with pytest.raises(InputError):
        MappingParams(R_reg=np.ones((3, 3)))
    with pytest.raises(InputError):
        MappingParams(workspace_min=[0, 0, 0], workspace_max=[0, 1, 1])


def numpy_follow(p_stylus, anchor_s, anchor_r, pos, L_prev, m, offsets, dmax):
    """The per-tick mapping written with the module's numpy functions (what Follower.step computes)."""
    p_t = stylus2target(p_stylus, anchor_s, anchor_r, m)
    L = position2lengths(p_t, offsets)
    step = np.abs(L - L_prev).max()
    if step > dmax:
        p_t = pos + (p_t - pos) * (dmax / step)
        L = position2lengths(p_t, offsets)
    L = np.clip(L, G.l_min, G.l_max)
    if np.abs(L - L_prev).max() > dmax:
        L = limit_lengths(L, L_prev, G, dmax / G.v_max)
    return p_t, L


small = st.lists(st.floats(-0.004, 0.004), min_size=3, max_size=3).map(np.array)


@settings(max_examples=150)
@given(vec, small, small, st.lists(st.floats(-2e-4, 2e-4), min_size=6, max_size=6).map(np.array),
       st.sampled_from([0.25, 1.0, 3.0]), st.floats(-0.3, 0.3))
def test_follower_step_equals_the_numpy_mapping(p_stylus, anchor_r, pos, L_jitter, scale, gamma):
    """Workspace clip, straight-line step limit and the hard length limit, against the numpy functions."""
    m = MappingParams(motion_scale=scale, home=[0.0, 0.0, 0.0, 0.0, 0.0, gamma])
    dt = 1e-3
    fol = Follower(m, G, dt)
    offsets = platform_offsets(G, m.home[3:])
    L_prev = np.clip(position2lengths(pos, offsets) + L_jitter, G.l_min, G.l_max)
    anchor_s = np.zeros(3)
    p_ref, L_ref = numpy_follow(p_stylus, anchor_s, anchor_r, pos, L_prev, m, offsets, G.v_max * dt)
    p_fast, L_fast = fol.step(p_stylus.tolist(), anchor_s.tolist(), anchor_r.tolist(), pos.tolist(),
                              L_prev.tolist())
    np.testing.assert_allclose(p_fast, p_ref, rtol=0, atol=1e-15)
    np.testing.assert_allclose(L_fast, L_ref, rtol=0, atol=1e-15)
    assert np.abs(np.array(L_fast) - L_prev).max() <= G.v_max * dt * (1 + 1e-12)


def test_follower_step_limit_moves_along_the_line():
    fol = Follower(MappingParams(), G, 1e-3)
    L0 = fol.lengths(0.0, 0.0, 0.0)
    p, L = fol.step([0.0, 0.0, -0.02], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], L0)
    assert p[0] == 0.0 and p[1] == 0.0 and 0.0 < p[2] < 0.005  # +z (the registration flips z), cut short
    step = np.abs(np.array(L) - L0).max()  # the line step is exact to first order in the target distance
    assert 0.8 * G.v_max * 1e-3 < step <= G.v_max * 1e-3
