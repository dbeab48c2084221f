"""Kinematics identities: IK -> FK round trips, symmetric pose, structure matrix, bending angles."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from teleop.core.errors import InfeasibleError, InputError
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import (bending_angles, is_tensionable, length_jacobian, lengths2pose, pose2cables,
                               pose2lengths, pose2lengths_checked, poses2lengths, rotation_zyx,
                               structure_matrix)

GEOM = default_geometry()
mm = 1e-3
angles = st.floats(-0.35, 0.35)
positions = st.floats(-6 * mm, 6 * mm)


def pose_from(x, y, z, beta, gamma):
    return np.array([x, y, z, 0.0, beta, gamma])


@given(positions, positions, positions, angles, angles)
def test_inverse_then_forward_round_trip(x, y, z, beta, gamma):
    q = pose_from(x, y, z, beta, gamma)
    back = lengths2pose(pose2lengths(q, GEOM), GEOM)
    assert np.abs(back[:3] - q[:3]).max() <= 1e-9  # m
    assert np.abs(back[3:] - q[3:]).max() <= 1e-9  # rad


@given(positions, positions, positions, angles, angles, st.integers(0, 5), st.floats(-1e-8, 1e-8))
def test_lengths_no_pose_has_stop_at_the_least_squares_pose(x, y, z, beta, gamma, i, dl):
    """One length moved off its pose (as the loop's per-cable step limit leaves them): the Gauss-Newton stops
    once its step is below tol, at the least-squares pose (J^T r = 0), instead of halving round-off steps
    until max_iter (which moved the pose by ~1e-13 rad per call)."""
    from teleop.core.kernels.geometry import forward_kinematics
    from teleop.core.kinematics import FREE_AXIAL

    q0 = pose_from(x, y, z, beta, gamma)
    L = pose2lengths(q0, GEOM).copy()
    L[i] += dl
    few, many = q0.copy(), q0.copy()
    forward_kinematics(L, few, FREE_AXIAL, GEOM.r, GEOM.B, 1e-12, 4)
    forward_kinematics(L, many, FREE_AXIAL, GEOM.r, GEOM.B, 1e-12, 100)
    assert np.array_equal(few, many)  # converged within 4 iterations, then stopped
    J = length_jacobian(many, GEOM)[:, FREE_AXIAL]
    r = pose2lengths(many, GEOM) - L
    assert np.abs(J.T @ r).max() <= 1e-11  # the normal equations hold (within tol): a least-squares pose


@given(st.floats(-np.pi, np.pi), st.floats(-1.5, 1.5), st.floats(-np.pi, np.pi))
def test_rotation_is_orthonormal_zyx(a, b, g):
    R = rotation_zyx(a, b, g)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    Rz = rotation_zyx(a, 0, 0)
    Ry = rotation_zyx(0, b, 0)
    Rx = rotation_zyx(0, 0, g)
    np.testing.assert_allclose(R, Rz @ Ry @ Rx, atol=1e-12)


def test_symmetric_pose_gives_six_equal_lengths_and_bends():
    L = pose2lengths(np.zeros(6), GEOM)
    np.testing.assert_allclose(L, L[0], rtol=0, atol=1e-15)
    theta = bending_angles(pose2cables(np.zeros(6), GEOM), GEOM)
    np.testing.assert_allclose(theta, np.arctan2(0.015, 0.020), atol=1e-12)  # elevation of each cable


@given(positions, positions, positions, angles, angles)
def test_batch_lengths_match_single(x, y, z, beta, gamma):
    q = pose_from(x, y, z, beta, gamma)
    np.testing.assert_allclose(poses2lengths(q[None], GEOM)[0], pose2lengths(q, GEOM), atol=1e-15)


@given(positions, positions, positions, angles, angles)
def test_structure_matrix_is_minus_jacobian_transpose(x, y, z, beta, gamma):
    """Virtual work: the translational rows of A are -dL/dp (cable pulls shorten the cable)."""
    q = pose_from(x, y, z, beta, gamma)
    A = structure_matrix(q, GEOM)
    J = length_jacobian(q, GEOM)
    np.testing.assert_allclose(A[:3].T, -J[:, :3], atol=1e-12)
    assert np.linalg.matrix_rank(A, tol=1e-9) == 5  # five cable-controlled DOF, one null direction


def test_bending_angle_is_elevation_above_base_plane():
    l = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -2.0]])
    np.testing.assert_allclose(bending_angles(l, GEOM), np.deg2rad([45.0, 0.0, 90.0]), atol=1e-12)


def test_nan_and_unreachable_poses_raise():
    with pytest.raises(InputError, match="finite"):
        pose2lengths_checked([0, 0, np.nan, 0, 0, 0], GEOM)
    with pytest.raises(InfeasibleError, match="unreachable"):
        pose2lengths_checked([0, 0, 0.08, 0, 0, 0], GEOM)
    with pytest.raises(InputError):
        lengths2pose([0.02] * 5, GEOM)


def test_home_pose_holds_pretension_and_far_tilt_does_not():
    assert is_tensionable(np.zeros(6), GEOM)
    # moving forward until the rear anchor is ahead of the ring plane: every cable pulls back, no pretension
    assert not is_tensionable(np.array([0, 0, 0.020, 0, 0, 0]), GEOM)
