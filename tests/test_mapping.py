"""teleop.mapping: scale, registration, workspace clamp, length limits and the per-tick step limit."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from teleop.errors import InputError
from teleop.geometry import default_geometry
from teleop.kinematics import pose2lengths, rotation_zyx
from teleop.mapping import (MappingParams, is_aligned, limit_lengths, platform_offsets, position2lengths,
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
