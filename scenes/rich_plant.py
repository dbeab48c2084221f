"""A plant richer than the estimators (`sim://robot?plant=rich`, `teleop palpate --plant rich`): effects of a
real tendon-sheath cable that none of the compensators models, switched on in every cable of the simulated
robot on top of its own sheath capstan friction (scenes.sim_robot).

Along one cable, from the motor to the FSR (x_c = the cable's travel, increasing while hauling in):

    backlash                     play between each motor and its cable (spool coupling): the simulated
                                 robot's own per-cable play operator (SimRobotParams.backlash, `with_plant`
                                 switches it on); the pose follows the realized lengths, and in the rich
                                 plant the sheath's friction travels with the realized cable, x_c = -L_real
                                 (within the play the cable does not move, so neither does its friction)
    t_tip --capstan--> (the simulated robot's own sheath friction, along x_c)
          + stribeck_friction(v_c)   load-independent sheath friction with a low-speed peak (the liner's
                                     seal and the cable's bending in the sheath), v_c = dx_c / dt
          + dahl_hysteresis(x_c)     pre-sliding with its own rest stiffness and sliding force (not the
                                     capstan's stick stiffness the estimators know)
          --pulley_friction(x_c)-->  the guide pulley where the cable leaves the scaffold for the FSR press
                                     block (seed 002's cable-pulley law, lumped: exp(mu wrap) band, bending
                                     loss, stick transitions)
          + thermal_drift_time(t)    FSR creep: the reading rises at `rate` under a sustained load, from the
                                     tare at power-on (t = 0)
    -> the FSR's own hysteresis, divider and ADC (scenes.sim_robot, unchanged).

Every formula is the catalogue's (teleop.core.physics: stribeck, the dahl_hysteresis, pulley_friction and
thermal_drift_time effects; the backlash play operator in scenes.sim_robot); this module only chains them
per cable and keeps each state in the catalogue's per-sample Steps, so the batch path (`SimRobot.run`, m
samples, the Steps' array forms) and the per-reading path (m = 1, the Steps) agree.

Parameters: `RichPlantParams` (nominal values and where each comes from); every cable draws its own
values, each nominal times exp(spread N(0, 1)) from `seed` (cables of one robot differ: different bends,
liners, press blocks and FSRs).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from teleop.core.errors import InputError
from teleop.core.physics import get_effect, stribeck

EFFECTS = ("backlash", "stribeck_friction", "dahl_hysteresis", "pulley_friction", "thermal_drift_time")
PLANTS = ("matched", "rich")


@dataclass(frozen=True)
class RichPlantParams:
    """Nominal parameters of the effects the estimators do not model (SI), and which are on.

    Attributes:
        effects: the catalogue effects switched on (a subset of EFFECTS; all by default).
        seed: seeds each cable's draw around the nominal values.
        spread: log-normal spread of every parameter between cables [-] (0.25: a cable's value within about
            0.6-1.6 x nominal, 95 %).
        backlash_width: play between each motor and its cable [m] (one width for the six: the simulated
            robot's SimRobotParams.backlash). 0.1 mm is an assumption (the seeds give no figure for the
            robot's spools): a set-screw spool on a NEMA17 shaft; at the palpation's cable speed (~0.3 mm/s)
            each reversal waits ~0.3 s before the cable moves.
        stribeck_Fc, stribeck_Fs: load-independent sliding and breakaway friction [N]; stribeck_vs: Stribeck
            velocity [m/s]. Seed 000 Fig 9a (theta 0, 1.96 N) shows a 0.54 N band at the FSR, which the
            capstan law with the robot's mu = 0.056 over theta0 = 140 deg accounts for in full
            (1.96 (e^0.137 - e^-0.137) = 0.54 N), so a load-independent part must be small beside it: Fc
            0.03 N (~5 % of that band), a breakaway peak Fs = 2 Fc (the static/kinetic ratio of a steel cable
            on a polymer liner is ~1.2-2), vs = 0.1 mm/s below the palpation's cable speed so the peak shows
            at slow starts and in the variable-speed profile.
        dahl_sigma, dahl_Fc: Dahl rest stiffness [N/m] and sliding force [N]: 400 N/m and 0.04 N give a
            pre-sliding transition over ~3 Fc / sigma = 0.3 mm of cable travel, longer than the robot's capstan
            stick (0.2 mm at 5e3 N/m) and of another shape (exponential, not linear); seed 000 [20] models
            pulley-bearing friction in a CDPR with Dahl's law, seed 000 §3 reports transitions after each
            reversal on the single-cable bench.
        pulley_mu, pulley_wrap, pulley_bend, pulley_k: the guide pulley (teleop.core.physics pulley_friction):
            equivalent friction coefficient [-] of a 6 mm plastic pulley on a steel pin (cable on pulley and
            the shaft's friction folded in, seed 002's nomenclature), 0.04; wrap 0.5 rad (the ~30 deg
            deflection into the press block); bending loss EI / R^2 [N]: a 0.3 mm 7x7 steel cable has EI
            between 5.7e-7 N m^2 (49 wires sliding freely, E = 200 GPa) and 8e-5 (solid), over R = 3 mm 0.06-9
            N elastic of which a stranded cable dissipates a small part: 0.02 N; stick stiffness 2e4 N/m
            (the catalogue default).
        drift_rate: FSR creep under a sustained load [N/s]: 1.4e-5 N/s = 0.05 N per hour, the drift seed
            000 Table 4 quotes for the multi-DOF cable-driven instrument of its ref [17]; the Interlink FSR
            datasheet gives < 5 % per decade of time under constant load (~0.14 N per decade at the 2.85 N
            pretension).
    """

    effects: tuple = EFFECTS
    seed: int = 0
    spread: float = 0.25
    backlash_width: float = 1.0e-4
    stribeck_Fc: float = 0.03
    stribeck_Fs: float = 0.06
    stribeck_vs: float = 1.0e-4
    dahl_sigma: float = 400.0
    dahl_Fc: float = 0.04
    pulley_mu: float = 0.04
    pulley_wrap: float = 0.5
    pulley_bend: float = 0.02
    pulley_k: float = 2.0e4
    drift_rate: float = 1.4e-5

    def __post_init__(self):
        bad = [e for e in self.effects if e not in EFFECTS]
        if bad:
            raise InputError(f"rich plant: unknown effect '{bad[0]}' (expected some of: {', '.join(EFFECTS)})")
        if not self.spread >= 0:
            raise InputError(f"rich plant: spread must be >= 0, got {self.spread}")

    def nominal(self) -> dict:
        """{effect: {parameter: nominal value}} of the effects switched on (catalogue parameter names)."""
        every = {"backlash": {"width": self.backlash_width},
                 "stribeck_friction": {"Fc": self.stribeck_Fc, "Fs": self.stribeck_Fs, "vs": self.stribeck_vs},
                 "dahl_hysteresis": {"sigma": self.dahl_sigma, "Fc": self.dahl_Fc},
                 "pulley_friction": {"mu": self.pulley_mu, "wrap": self.pulley_wrap, "bend": self.pulley_bend,
                                     "k": self.pulley_k},
                 "thermal_drift_time": {"offset": 0.0, "rate": self.drift_rate}}
        return {e: every[e] for e in EFFECTS if e in self.effects}


# parameters that are geometry, not a cable's scatter (the pulley's wrap is the press block's layout)
_FIXED = {("pulley_friction", "wrap"), ("thermal_drift_time", "offset")}


def with_plant(sim, plant: RichPlantParams | None):
    """The simulated robot's parameters (scenes.sim_robot.SimRobotParams) with `plant` on: its per-cable
    effects, and its backlash as the robot's own motor play."""
    if plant is None:
        return dataclasses.replace(sim, plant=None)
    play = plant.backlash_width if "backlash" in plant.effects else sim.backlash
    return dataclasses.replace(sim, plant=plant, backlash=play)


def draw_cables(params: RichPlantParams, n: int) -> list:
    """Per cable {effect: {parameter: value}} of the effects this module applies (all but backlash, the
    robot's own): each nominal times exp(spread z), z ~ N(0, 1) from the seed, checked against the catalogue's
    parameter specs."""
    rng = np.random.default_rng(np.random.SeedSequence([int(params.seed), 16]))
    nominal = {e: p for e, p in params.nominal().items() if e != "backlash"}
    out = []
    for _ in range(n):
        cable = {}
        for eff, p in nominal.items():
            vals = {k: (v if (eff, k) in _FIXED else v * math.exp(params.spread * rng.standard_normal()))
                    for k, v in p.items()}
            if eff == "stribeck_friction":  # the breakaway peak stays at or above the sliding friction
                vals["Fs"] = max(vals["Fs"], vals["Fc"])
            cable[eff] = get_effect(eff).check(vals)
        out.append(cable)
    return out


class RichPlant:
    """The added effects of every cable; their states live in the catalogue's per-sample Steps.

        plant = RichPlant(RichPlantParams(seed=1), n=6)
        F = plant.forces(F_capstan, x_c, t)  # (m, n) tension past the capstan [N] -> what the FSR feels [N]

    x_c (m, n): the cables' travel [m]; call once per batch of m readings, in time order (t (m,) [s] after
    power-on).
    One reading (m = 1) steps the Steps; a batch runs the array forms from the Steps' states and leaves
    the final states in them, so both paths give the same numbers (tested).
    """

    def __init__(self, params: RichPlantParams, n: int = 6):
        self.params = params
        self.n = int(n)
        self.cables = draw_cables(params, self.n)
        self.on = set(params.effects)
        self.steps = [{e: get_effect(e).make_step(p) for e, p in c.items()} for c in self.cables]
        for st in self.steps:
            if "thermal_drift_time" in st:
                st["thermal_drift_time"].step(t=0.0, force=0.0)   # the tare at power-on: t0 = 0
        self._xc = None       # previous sheath travel (n,) [m]
        self._t = math.nan    # previous reading time [s]

    def describe(self) -> dict:
        """JSON-ready: the effects on and each cable's drawn parameters."""
        return {"effects": [e for e in EFFECTS if e in self.on], "seed": self.params.seed,
                "spread": self.params.spread, "backlash_width_m": self.params.backlash_width
                if "backlash" in self.on else 0.0, "cables": self.cables}

    def forces(self, F, xc, t) -> np.ndarray:
        """(m, n) tension at the FSR [N]: F (m, n) the tension past the sheath's capstan [N], xc (m, n) the
        cables' travel [m], t (m,) reading times [s] after power-on (> 0, increasing)."""
        F = np.asarray(F, dtype=float)
        xc = np.asarray(xc, dtype=float)
        t = np.asarray(t, dtype=float).reshape(-1)
        # sheath velocity by differences from the previous reading (0 at the first)
        xp = xc[0] if self._xc is None else self._xc
        tt = np.concatenate([[t[0] if math.isnan(self._t) else self._t], t])
        dx = np.diff(np.vstack([xp[None], xc]), axis=0)
        v = np.divide(dx, np.diff(tt)[:, None], out=np.zeros_like(dx), where=np.diff(tt)[:, None] > 0)
        out = self._step(F, xc, t, v) if len(t) == 1 else self._run(F, xc, t, v)
        self._xc, self._t = xc[-1].copy(), float(t[-1])
        return out

    def _step(self, F, xc, t, v) -> np.ndarray:
        out = np.empty((1, self.n))
        tk = float(t[0])
        for i, st in enumerate(self.steps):
            f, x = float(F[0, i]), float(xc[0, i])
            if "stribeck_friction" in st:
                f = st["stribeck_friction"].step(v=float(v[0, i]), load=f)
            if "dahl_hysteresis" in st:
                f = st["dahl_hysteresis"].step(x=x, load=f)
            if "pulley_friction" in st:
                f = st["pulley_friction"].step(x=x, load=f)
            if "thermal_drift_time" in st:
                f = st["thermal_drift_time"].step(t=tk, force=f)
            out[0, i] = f
        return out

    def _run(self, F, xc, t, v) -> np.ndarray:
        out = np.empty_like(F)
        for i, st in enumerate(self.steps):
            f, x = F[:, i].copy(), xc[:, i]
            if "stribeck_friction" in st:
                s = st["stribeck_friction"].params
                f += stribeck(v[:, i], s["Fc"], s["Fs"], s["vs"])
            if "dahl_hysteresis" in st:   # the array forms from the Steps' states, which they leave at the end
                f = st["dahl_hysteresis"].run(x=x, load=f)
            if "pulley_friction" in st:
                f = st["pulley_friction"].run(x=x, load=f)
            if "thermal_drift_time" in st:  # drift since the tare at power-on, t = 0
                f = st["thermal_drift_time"].run(t=t, force=f)
            out[:, i] = f
        return out


def plant_params(plant: str, seed: int) -> RichPlantParams | None:
    """The simulated robot's `plant` option: None for "matched" (the robot's physics is the estimators'
    model), RichPlantParams(seed=seed) for "rich"."""
    if plant not in PLANTS:
        raise InputError(f"unknown plant '{plant}' (expected one of: {', '.join(PLANTS)})")
    return None if plant == "matched" else RichPlantParams(seed=int(seed))
