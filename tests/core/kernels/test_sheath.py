"""The sheath's one home (teleop.core.kernels.sheath): its parameters, its state layout, the start on the tip
tension, the forward law and its inverse, and the readers that take them from there."""

import math

import numpy as np
import pytest

from scenes.sim_robot import SimRobotParams
from teleop.core.errors import InputError
from teleop.core.estimation.estimators import DynamicParams
from teleop.core.estimation.tick import TickComputer
from teleop.core.geometry import default_geometry
from teleop.core.kernels import estimate as K
from teleop.core.kernels import sheath as SH
from teleop.core.physics import get_effect


@pytest.mark.parametrize("field", ["mu", "theta0", "stick_k", "pretension"])
@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
def test_parameters_must_be_finite_and_nonnegative(field, bad):
    with pytest.raises(InputError, match="sheath"):
        SH.Sheath(**{field: bad})


def test_constants_follow_the_layout_and_the_readers_take_them_from_the_sheath():
    s = SH.Sheath(mu=0.1, theta0=2.0, stick_k=3e3, pretension=1.5)
    c = s.constants()
    assert c.shape == (SH.N_CONST,) and (c[SH.MU], c[SH.THETA0], c[SH.STICK_K], c[SH.PRETENSION]) == (0.1, 2.0, 3e3, 1.5)
    g = default_geometry()
    assert (g.mu, g.theta0) == (SH.Sheath.mu, SH.Sheath.theta0)
    sim = SimRobotParams()
    assert sim.sheath == SH.Sheath() and DynamicParams().capstan_k == SH.Sheath.stick_k
    assert get_effect("capstan_friction").spec("k").default == SH.STIFF_STICK_K != SH.Sheath.stick_k
    tc = TickComputer(g, "dynamic", dynamic=DynamicParams(capstan_k=7e3))
    np.testing.assert_array_equal(tc.c[:SH.N_CONST], SH.Sheath(mu=g.mu, theta0=g.theta0, stick_k=7e3).constants())
    # the estimator's state starts with the sheath's, before any sample
    np.testing.assert_array_equal(tc.st[:SH.N_STATE], SH.new_state(len(g.B)))
    assert tc.st.shape[0] == K.N_ROWS


def test_the_first_sample_starts_on_the_tip_tension():
    c = SH.Sheath(mu=0.2, stick_k=1e3).constants()
    st = SH.new_state(2)
    assert SH.motor_force(st, 1, 0.01, 3.0, 2.0, c) == 3.0
    assert st[SH.X, 1] == 0.01 and math.isnan(st[SH.X, 0])
    assert SH.tip_tension(st, 0, 0.0, 3.0, 2.0, c) == 3.0  # phi = 0: the inverse starts there too


def test_the_inverse_recovers_the_tip_tension_through_reversals():
    """A cable at a constant tip tension hauled in and paid out: the forward law's FSR force leaves the tip
    tension at every reversal, and the inverse with the same sheath gives the tip tension back."""
    c = SH.Sheath(mu=0.1, stick_k=5e3).constants()
    theta = 3.0
    x = 2e-3 * np.sin(np.linspace(0.0, 6 * np.pi, 6000))
    t_tip = np.full(x.size, 2.0)
    fwd = SH.new_state(1)
    F = SH.motor_force_run(x, t_tip, np.full(x.size, theta), c, fwd, 0, np.empty(x.size))
    band = (2.0 * math.exp(-0.1 * theta), 2.0 * math.exp(0.1 * theta))
    assert F.min() == pytest.approx(band[0], rel=1e-12) and F.max() == pytest.approx(band[1], rel=1e-12)
    assert np.mean((F > band[0] * (1 + 1e-9)) & (F < band[1] * (1 - 1e-9))) > 0.05  # the stick transitions
    inv = SH.new_state(1)
    dx = np.diff(x, prepend=x[0])
    t = np.array([SH.tip_tension(inv, 0, dx[j], F[j], theta, c) for j in range(x.size)])
    np.testing.assert_allclose(t, t_tip, rtol=5e-3)  # the inverse steps phi linearly: d phi = k dx / (mu Theta F)
    assert np.abs(t - t_tip).max() < 0.1 * np.abs(F - t_tip).max()
