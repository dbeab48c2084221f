"""Pad contact: the force an indenter feels at indentation d [m] (d <= 0: no contact, zero force).

- linear_contact:  F = k d                                   k [N/m]
- hertz_contact:   F = k d^1.5                               k [N/m^1.5] (sphere on a half-space)
- viscoelasticity: standard linear solid acting on the elastic force Fe of the channel `force` (the
  quasi-linear form): F = g Fe + q, dq/dt = (1 - g) dFe/dt - q / tau. With Fe = k d this is the SLS of
  instantaneous stiffness k, relaxed stiffness g k and relaxation time tau: under a held indentation F
  relaxes from k d to g k d; faster indentation gives more force. Discretised exactly for Fe linear over
  each sample interval: q_k = a q_k-1 + (1 - g) (dFe/dt) tau (1 - a), a = exp(-dt / tau).
- contact_damping: F = Fe + c d_dot while in contact, never pulling (F >= 0), zero out of contact.
Every contact force is zero without contact and never negative. Each effect's physics is one step kernel
(teleop.core.kernels.effects); the array forms are the catalogue's driver loop over it.
"""

from __future__ import annotations

import math
import numpy as np

from teleop.core.kernels.effects import contact_damping_run, contact_damping_step, hertz_contact_run, \
    hertz_contact_step, linear_contact_run, linear_contact_step, viscoelasticity_run, viscoelasticity_step
from teleop.core.physics.base import Effect, Kernel, ParamSpec, Rules, Signals, kernel_call, register

LINEAR = Kernel(linear_contact_step, linear_contact_run, state=())
HERTZ = Kernel(hertz_contact_step, hertz_contact_run, state=())
SLS = Kernel(viscoelasticity_step, viscoelasticity_run, state=(math.nan, 0.0, 0.0))
DAMPING = Kernel(contact_damping_step, contact_damping_run, state=())


def linear_force(d, k):
    """Spring contact force [N]: k max(d, 0)."""
    return kernel_call(LINEAR, (k,), d)


def hertz_force(d, k):
    """Hertz contact force [N]: k max(d, 0)^1.5."""
    return kernel_call(HERTZ, (k,), d)


def sls_force(t, Fe, d, g, tau):
    """(n,) viscoelastic contact force [N] from the elastic force Fe (n,) [N], indentation d (n,) [m]."""
    return kernel_call(SLS, (g, tau), t, Fe, d)


def damped_force(Fe, d, d_dot, c):
    """Contact force [N] with damping c [N s/m]: max(Fe + c d_dot, 0) in contact, else 0."""
    return kernel_call(DAMPING, (c,), Fe, d, d_dot)


def _loaded(s: Signals, y: np.ndarray) -> np.ndarray:
    return (s.d > 0.05 * max(float(s.d.max()), 1e-300)) & (y > 0)


def _linear_guess(s: Signals, y: np.ndarray) -> dict:
    m = _loaded(s, y)
    return {"k": float(np.median(y[m] / s.d[m]))} if m.any() else {}


def _hertz_guess(s: Signals, y: np.ndarray) -> dict:
    m = _loaded(s, y)
    return {"k": float(np.median(y[m] / s.d[m] ** 1.5))} if m.any() else {}


def _sls_guess(s: Signals, y: np.ndarray) -> dict:
    m = (s.force > 0.2 * max(float(s.force.max()), 1e-300)) & (y > 0)
    g = float(np.percentile(y[m] / s.force[m], 5)) if m.any() else 0.5
    return {"g": g, "tau": 0.05 * float(s.t[-1] - s.t[0])}


def _damping_guess(s: Signals, y: np.ndarray) -> dict:
    m = (s.d > 0) & (y > 0) & (np.abs(s.d_dot) > 0)
    if not m.any():
        return {}
    c = float(np.dot(s.d_dot[m], (y - s.force)[m]) / np.dot(s.d_dot[m], s.d_dot[m]))
    return {"c": c} if c > 0 else {}


LINEAR_CONTACT = register(Effect(
    name="linear_contact", link="contact", doc="spring pad: F = k d in contact",
    params=(ParamSpec("k", "N/m", 1.0, 1e7, 500.0, "pad stiffness", log=True),),
    inputs=("d",), output="force",
    guess=_linear_guess, kernel=LINEAR,
    rules=Rules(channel="force", primary=("k",), finding=False)))   # the contact baseline's own law

HERTZ_CONTACT = register(Effect(
    name="hertz_contact", link="contact", doc="Hertz pad: F = k d^1.5 in contact",
    params=(ParamSpec("k", "N/m^1.5", 1.0, 1e9, 1e4, "Hertz coefficient (4/3 E* sqrt(R))", log=True),),
    inputs=("d",), output="force",
    guess=_hertz_guess, kernel=HERTZ,
    rules=Rules(channel="force", primary=("k",),
                draw=lambda rng, s: {"k": s.stiffness / math.sqrt(rng.uniform(2e-3, 5e-3))})))

VISCOELASTICITY = register(Effect(
    name="viscoelasticity", link="contact",
    doc="standard linear solid on the elastic force: relaxation to g Fe with time constant tau",
    params=(ParamSpec("g", "1", 0.0, 1.0, 0.6, "relaxed / instantaneous stiffness ratio"),
            ParamSpec("tau", "s", 1e-4, 1e4, 1.0, "relaxation time", log=True, positive=True)),
    inputs=("t", "force", "d"), output="force",
    guess=_sls_guess, kernel=SLS,
    # a relaxation faster than the data resolve (tau below twice the inputs' smoothing) is damping
    rules=Rules(channel="force", primary=("g", "tau"), wrong_form=lambda p, rec: p["tau"] < 2.0 * rec.resolution_s,
                draw=lambda rng, s: {"g": rng.uniform(0.4, 0.8), "tau": rng.uniform(0.2, 1.5)})))

CONTACT_DAMPING = register(Effect(
    name="contact_damping", link="contact", doc="F = Fe + c d_dot in contact, never pulling",
    params=(ParamSpec("c", "N s/m", 1e-4, 1e6, 5.0, "contact damping coefficient", log=True),),
    inputs=("force", "d", "d_dot"), output="force",
    guess=_damping_guess, kernel=DAMPING,
    rules=Rules(channel="force", primary=("c",),
                draw=lambda rng, s: {"c": rng.uniform(0.15, 0.4) * s.stiffness * s.travel / s.v_fast})))
