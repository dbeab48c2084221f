"""Tension distribution: A t + f = 0 with t in bounds, errors outside the wrench-feasible set."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from teleop.core.errors import InfeasibleError
from teleop.core.geometry import default_geometry
from teleop.core.kinematics import structure_matrix
from teleop.core.tension import tensions2wrench, wrench2tensions

GEOM = default_geometry()
mm = 1e-3


@given(st.floats(-5 * mm, 5 * mm), st.floats(-5 * mm, 5 * mm), st.floats(-5 * mm, 5 * mm),
       st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.lists(st.floats(0.4, 4.5), min_size=6, max_size=6))
def test_distribution_then_wrench_returns_the_wrench(x, y, z, beta, gamma, t_true):
    """Any wrench made by in-bounds tensions is reproduced exactly by the distributed tensions."""
    A = structure_matrix([x, y, z, 0, beta, gamma], GEOM)
    f = tensions2wrench(np.array(t_true), A)
    t = wrench2tensions(f, A, GEOM.t_min, GEOM.t_max, t_ref=1.5)
    assert (t >= GEOM.t_min - 1e-12).all() and (t <= GEOM.t_max + 1e-12).all()
    np.testing.assert_allclose(tensions2wrench(t, A), f, atol=1e-9)


def test_zero_wrench_gives_pretension_near_reference():
    A = structure_matrix(np.zeros(6), GEOM)
    t = wrench2tensions(np.zeros(6), A, GEOM.t_min, GEOM.t_max, t_ref=1.5)
    np.testing.assert_allclose(t, 1.5, atol=1e-12)


def test_moment_about_shaft_axis_is_infeasible():
    A = structure_matrix(np.zeros(6), GEOM)
    with pytest.raises(InfeasibleError, match="shaft axis"):
        wrench2tensions([0, 0, 0, 0, 0, 0.01], A, GEOM.t_min, GEOM.t_max)


def test_wrench_beyond_tension_bounds_is_infeasible():
    A = structure_matrix(np.zeros(6), GEOM)
    with pytest.raises(InfeasibleError, match="wrench-feasible"):
        wrench2tensions([0, 0, -100.0, 0, 0, 0], A, GEOM.t_min, GEOM.t_max)


def test_nan_wrench_is_refused():
    A = structure_matrix(np.zeros(6), GEOM)
    with pytest.raises(InfeasibleError, match="finite"):
        wrench2tensions([np.nan, 0, 0, 0, 0, 0], A, GEOM.t_min, GEOM.t_max)
