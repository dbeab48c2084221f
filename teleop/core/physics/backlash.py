"""Backlash (play, dead band) between the motor and the tip: the play operator, and its general form.

Plain form (width only): the tip position y follows the motor position x only once the play of total width
w is taken up: y_k = clamp(y_k-1, x_k - w/2, x_k + w/2), starting centred (y_0 = x_0). While x moves inside
the dead band y stays put; while x drives, y = x -/+ w/2 (lagging behind the motion).

General form (a tendon in a sheath, measured on a surgical instrument's jaw): the dead band is not all dead
and not all of one width. A part of the motion (`elastic`) reaches the tip at once (the preloaded cable's
stretch unloads first); of the rest, a fraction `tail` is taken up only over a band TAIL_RATIO times wider
(sheath friction slipping progressively along the tendon: a slow creep after the main take-up); and the lag
scales as e^(grow (x - x_ref)) with the tip's position x (the tendon's tension, and so the friction's
stretch, changes along the stroke; the scale is 1 at x_ref, where `elastic` is the part that follows at
once; a fit holds x_ref at the record's mean tip position). `start` in [-1, 1] is where in its band each play was
when the record began (0: centred). This is a Prandtl-Ishlinskii operator with three play widths (0, w,
TAIL_RATIO w) and a position-dependent output scale.

Tension (a tendon pulling a spring through a sheath of friction; Kaneko et al., ICAR 1991): after a reversal
the cable's tension profile turns over from the motor end towards the tip, T e^(+-mu kappa s), and with uniform
friction the tip stays put until the turn-over reaches it (a sharp take-up: the whole profile is then the
new sliding one). The dead zone is the difference of the two sliding profiles' stretches, 2 T L (cosh(mu
Theta) - 1) / (EA mu Theta), proportional to the tension T at the reversal; their common part, the elastic
stretch T L / EA times a mean of the profile, is linear in T as well and goes to the link's gain. Under a
spring the tip's position is its tension (up to the preload), so the main play's half-width grows linearly
with its position: width / 2 (1 + tension (z - x_ref)), its envelopes z = x -/+ width / 2 (1 + tension z)
solved in closed form (kernels.tension_play); Kaneko's tension = 1 / (x_ref - the slack tip position). For
the tip position this is the quasi-static distributed model itself, not an approximation of it: the tip
moves only on a branch where the whole profile slides, and there its stretch is that branch's.

Load tension (a tendon pulling an external force: the tension is no function of the tip's position): where
the link records the tip load T (the `load` channel: the tip force), the main play's half-width grows with
its magnitude, width / 2 (1 + load_tension (|T| - load) / load), `load` the magnitude at which it is `width`
(a fit holds it at the record's mean |T|; where no load is recorded it stands in for it, and nothing grows).
Kaneko's dead zone is proportional to the cable's tension, the load plus any pretension P: load_tension =
load / (load + P), within [0, 1] (1: no pretension); a dead zone shrinking with the load is no sheath's. The
spring's `tension` is the special case where the tip's position is the only proxy of T: both enter one
half-width, r1 (1 + load_tension (|T| - load) / load + tension (z - x_ref)), one closed form. The elastic
stretch common to both branches (linear in T) is cable_compliance's, not the play's.

Take-up (pre-sliding along the sheath): the sharp play's tip stands until an envelope reaches it and then
follows at a corner; a sheath whose friction builds over a pre-sliding travel (Dahl's exponential approach,
the partial-sliding zone of Kaneko's transmission before the whole profile slides) rounds that corner. With
`take_up` > 0 the main play moves before its envelope reaches it, at the envelope's rate times e^(-D / lam),
D its distance to the envelope, lam = take_up width / 2 the take-up length: over the dead zone the tip all
but stands, and it joins the envelope over a travel of a few lam (kernels.tension_play.take_up_gap, exact over
a sample); its steady lag is the sharp play's. take_up = 0 is the sharp take-up, bit for bit.

With elastic = tail = grow = tension = load_tension = take_up = start = 0 it is the plain play. The physics is one
step kernel (kernels.tension_play.backlash_step: the plain play kernels.effects.plain_play_step, or the general one over
kernels.friction.play_mix_step); the array form is the catalogue's driver loop over it.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from teleop.core.kernels.tension_play import backlash_run, backlash_step
from teleop.core.physics.base import Effect, Kernel, KernelStep, ParamSpec, Rules, Signals, drive_kernel, register

TAIL_RATIO = 4.0   # the wide play's width over the main play's
#: largest |b| = width tension / 2 of the main play's envelopes (x -/+ width / 2) / (1 +/- b): its dead zone
#: may not grow as fast as the play moves
TENSION_B_MAX = 0.9


def backlash(x: np.ndarray, width: float, y0: float | None = None) -> np.ndarray:
    """(n,) tip position [m or rad] from motor position x (n,) with play of total width [same unit], the
    play's position before x[0] at y0 (default: x[0])."""
    x = np.asarray(x, dtype=float)
    state = np.array([np.nan if y0 is None else float(y0), np.nan, np.nan, np.nan])
    p = BACKLASH.check({"width": width})
    return drive_kernel(KERNEL, state, np.column_stack([x, np.full(x.shape, p["load"])]), pack(p))


def mix_layout(p: Mapping[str, float]) -> tuple[float, float, float, float]:
    """(r1, r2, w1, w2): half-widths and weights of the main and the wide play of the general form."""
    main = 0.5 * p["width"]
    rest = 1.0 - p["elastic"]
    return main, TAIL_RATIO * main, rest * (1.0 - p["tail"]), rest * p["tail"]


def is_plain(p: Mapping[str, float]) -> bool:
    """True when the general form's parameters are all at the plain play's values."""
    return (p["elastic"] == 0.0 and p["tail"] == 0.0 and p["grow"] == 0.0 and p["start"] == 0.0
            and p["tension"] == 0.0 and p["load_tension"] == 0.0 and p["take_up"] == 0.0)


def pack(p: Mapping[str, float]) -> tuple:
    """The step kernel's parameters (kernels.tension_play.backlash_step): mix_layout, grow, start, x_ref,
    whether the form is plain (fixed with the parameters: decided once, not per sample), b = width
    tension / 2 (within +-TENSION_B_MAX), c = load_tension / load [1/N] (0 at a zero load), the load's
    reference magnitude and the take-up length take_up width / 2 [m or rad]."""
    b = min(max(0.5 * p["width"] * p["tension"], -TENSION_B_MAX), TENSION_B_MAX)
    c = p["load_tension"] / p["load"] if p["load"] > 0 else 0.0
    return mix_layout(p) + (p["grow"], p["start"], p["x_ref"], float(is_plain(p)), b, c, p["load"],
                            0.5 * p["width"] * p["take_up"])


#: state: the main and the wide play, the main play's envelopes at the last sample (a rounded take-up's)
KERNEL = Kernel(backlash_step, backlash_run, state=(np.nan, np.nan, np.nan, np.nan), pack=pack)


def _guess(signals: Signals, y: np.ndarray) -> dict:
    # while driving, x - y = +/- w/2: the spread of x - y is the full width
    e = signals.x - y
    return {"width": float(np.percentile(e, 98) - np.percentile(e, 2))}


PARAMS = (ParamSpec("width", "m", 1e-8, 100.0, 5e-4, "total play (dead band) width; rad for a rotary joint (a tendon-sheath joint can lose radians)",
                    log=True),
          ParamSpec("elastic", "1", 0.0, 0.95, 0.0, "fraction of the motion that reaches the tip at once "
                    "(general form)", shape=True),
          ParamSpec("tail", "1", 0.0, 0.95, 0.0, f"fraction of the play taken up over a {TAIL_RATIO:g}x wider "
                    "band (general form)", shape=True),
          ParamSpec("grow", "1/m", -50.0, 50.0, 0.0, "the lag scales as exp(grow (x - x_ref)) with the tip "
                    "position x (1/rad for a rotary joint; general form)", shape=True),
          ParamSpec("x_ref", "m", -1e6, 1e6, 0.0, "where the lag's scale is 1 (fits hold it at the record's mean "
                    "tip position; general form)", shape=True),
          ParamSpec("tension", "1/m", -1e4, 1e4, 0.0, "the main play's width grows as (1 + tension (z - x_ref)) "
                    "with its position z (a spring's tension; Kaneko: 1 / (x_ref - the slack tip position); 1/rad "
                    "for a rotary joint; general form)", shape=True, log=True, tiny=1.0,
                    alone=True),
          ParamSpec("load_tension", "1", 0.0, 2.0, 0.0, "the main play's width grows as (1 + load_tension "
                    "(|T| - load) / load) with the tip load T the link records (an external force's tension; "
                    "Kaneko: load / (load + the cable's pretension), 1 without one; general form)", shape=True,
                    alone=True),
          ParamSpec("load", "N", 0.0, 1e9, 0.0, "the tip load's magnitude at which the main play is `width` wide "
                    "(fits hold it at the record's mean |load|); where the link records no load it stands in "
                    "for it (N m for a torque; general form)", shape=True),
          ParamSpec("take_up", "1", 0.0, 1.0, 0.0, "the main play's take-up length over its half-width: the tip "
                    "joins the motion over a travel of a few take_up width / 2 after the dead zone instead of at a "
                    "corner (pre-sliding along the sheath; 0: the sharp take-up; general form)", shape=True,
                    alone=True),
          ParamSpec("start", "1", -1.0, 1.0, 0.0, "where in its band the play began (-1 .. 1, 0 centred; "
                    "general form)", shape=True, state=True))


class BacklashStep(KernelStep):
    """Per-sample backlash: step(x) -> tip position; `y` the plain play's position (None before the first
    sample)."""

    effect_name = "backlash"

    @property
    def y(self) -> float | None:
        return None if np.isnan(self.state[0]) else float(self.state[0])

    @y.setter
    def y(self, value: float) -> None:
        self.state[0] = value


def _hold(rec, known, direction) -> dict:
    """The general form's width (and its growth with the tension) refers to the record's mean tip position
    and its mean load magnitude (none recorded: 0, where the stand-in load gives no growth, and load_tension,
    which then changes nothing, is held at its plain 0)."""
    if rec.load is None:
        return {"x_ref": float(np.mean(rec.tip)), "load": 0.0, "load_tension": 0.0}
    return {"x_ref": float(np.mean(rec.tip)), "load": float(np.mean(np.abs(rec.load)))}


BACKLASH = register(Effect(
    name="backlash",
    link="position",
    doc="play operator: tip = clamp(tip_prev, motor - width/2, motor + width/2); general form: an elastic "
        "part, a wider slow play, a lag growing with position and a dead zone growing with the tension "
        "(the tip's position under a spring, the recorded tip load under a force: a tendon in a sheath)",
    params=PARAMS,
    inputs=("x",),
    optional=("load",),
    output="x",
    guess=_guess,
    kernel=KERNEL,
    step_class=BacklashStep,
    # a wide play flattens the affine least-squares gain (the tip stands still over the dead band): refit
    # from gains up to 1 / (1 - play fraction) larger
    rules=Rules(channel="tip_pos", primary=("width",), gain_restarts=(1.5, 2.5, 4.0), hold=_hold,
                draw=lambda rng, s: {"width": rng.uniform(0.08, 0.25) * 2 * s.travel}, raw_input=True,
                input_units=("width",)),
))
