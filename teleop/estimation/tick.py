"""The compute of one loop tick, hand-inlined on plain floats: pose -> cable lengths -> wrench -> stylus force.

    tc = TickComputer(geom, "dynamic", renderer=Renderer(RenderParams.for_device(spec)))
    lengths, wrench, force = tc.compute(pose, tensions, dt, velocity)

pose (6,) [x, y, z, alpha, beta, gamma] (m, rad, Z-Y-X Euler) of the end effector target; tensions (6,)
calibrated FSR tensions [N]; dt [s]; velocity (3,) stylus velocity [m/s] in the device frame (passivity).
Returns lengths: list of 6 cable lengths [m] (inverse kinematics, eq 4-5: command these to the robot);
wrench: list of 6 filtered wrench values [N, N m] in {B}; force: tuple (3,) stylus force [N] (device frame).

It computes exactly what `make_estimator(name, ...)` followed by `Renderer.render` compute (tests compare
them sample by sample to 1e-9), but with Python floats instead of numpy calls on 6-element arrays: at this
size numpy's per-call overhead (~1 us) dominates, while a float operation costs ~30 ns. The steps are
the same formulas as teleop.kinematics (eqs 4-6, 8), teleop.physics.capstan (motor2tip, capstan_band),
teleop.physics.friction (viscous, DahlStep), estimation.turn and estimation.direction; the Kalman step is
`SteadyWrenchKalman.update` inlined on that object's state, and the renderer is `Renderer.render_xyz`.
A non-finite input propagates to a renderer fault (zero force); call `reset()` after a fault.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.errors import InputError
from teleop.estimation.estimators import ESTIMATOR_NAMES, DynamicParams
from teleop.estimation.kalman import KalmanNoise, SteadyWrenchKalman, wrench_kalman_params
from teleop.estimation.turn import TurnCompensation
from teleop.geometry import Geometry
from teleop.rendering import Renderer


class TickComputer:
    """One tick's compute for the loop (see module docstring). `name` is the estimator's DESIGN.md name."""

    def __init__(self, geom: Geometry, estimator: str = "dynamic", *, turn: TurnCompensation | None = None,
                 dynamic: DynamicParams = DynamicParams(), kalman: KalmanNoise | None = KalmanNoise(),
                 renderer: Renderer | None = None, length_deadband: float = 0.0):
        if estimator not in ESTIMATOR_NAMES:
            raise InputError(f"unknown estimator '{estimator}' (expected one of: {', '.join(ESTIMATOR_NAMES)})")
        if estimator == "double" and turn is None:
            raise InputError("estimator 'double' needs a fitted turn compensation (fit_turn_compensation)")
        self.name = estimator
        self.mode = ESTIMATOR_NAMES.index(estimator)
        self.geom = geom
        self.cables = tuple(tuple(map(float, (*r, *b))) for r, b in zip(geom.r, geom.B))  # (rx, ry, rz, Bx, By, Bz)
        self.v = tuple(map(float, geom.v))
        self.theta0 = float(geom.theta0)
        self.mu = float(geom.mu)
        self.db = float(length_deadband)
        self.dyn = dynamic
        self.turn_axes = [] if turn is None or estimator != "double" else [
            (f.axis, f.duration, f.deadband, [list(map(float, c)) for c in f.forward],
             [list(map(float, c)) for c in f.backward]) for f in turn.axes]
        self.kalman = SteadyWrenchKalman(wrench_kalman_params(geom, kalman)) if kalman is not None else None
        self.renderer = renderer if renderer is not None else Renderer()
        self.reset()

    def reset(self) -> None:
        """Forget every state (directions, friction states, Kalman, renderer fault and ramp)."""
        self.dir = [0.0] * 6
        self.ext = [math.nan] * 6
        self.L_prev = None
        self.vel = [0.0] * 6
        self.F_dahl = [0.0] * 6
        self.phi = [0.0] * 6
        self.turn_state = [[0.0, math.nan, math.inf] for _ in self.turn_axes]  # direction, extreme, tau
        if self.kalman is not None:
            self.kalman.reset()
        self.renderer.reset()

    def compute(self, pose, tensions, dt: float, velocity=(0.0, 0.0, 0.0)):
        """(lengths [6], wrench [6], force (3,)) for one tick; see the module docstring."""
        lengths, w = self.estimate(pose, tensions, dt)
        return lengths, w, self.renderer.render_xyz(w[0], w[1], w[2], dt, *velocity)

    def estimate(self, pose, tensions, dt: float):
        """(lengths [6], wrench [6]): the tick without the renderer."""
        if isinstance(pose, np.ndarray):
            pose = pose.tolist()
        if isinstance(tensions, np.ndarray):
            tensions = tensions.tolist()
        x, y, z, a, b, g = pose
        sin, cos, sqrt, exp, asin = math.sin, math.cos, math.sqrt, math.exp, math.asin
        # R = Rz(a) Ry(b) Rx(g) (eq 5)
        ca, sa, cb, sb, cg, sg = cos(a), sin(a), cos(b), sin(b), cos(g), sin(g)
        R00, R01, R02 = ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg
        R10, R11, R12 = sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg
        R20, R21, R22 = -sb, cb * sg, cb * cg
        vx, vy, vz = self.v
        mu, th0, db, mode = self.mu, self.theta0, self.db, self.mode
        dirs, ext = self.dir, self.ext
        L_prev = self.L_prev
        first = L_prev is None
        lengths = [0.0] * 6
        fx = fy = fz = mx = my = mz = 0.0
        if mode == 3:
            dyn = self.dyn
            b_visc, Fc, sig = dyn.b, dyn.dahl_Fc, dyn.dahl_sigma
            a_v = dt / (dyn.v_smooth + dt) if dt > 0 else 0.0
            vel, F_dahl, phi = self.vel, self.F_dahl, self.phi
            k_st = dyn.capstan_k
        for i, (rx, ry, rz, Bx, By, Bz) in enumerate(self.cables):
            # R r_i, cable vector l_i = p + R r_i - B_i (eq 4-5), length, unit vector
            qx = R00 * rx + R01 * ry + R02 * rz
            qy = R10 * rx + R11 * ry + R12 * rz
            qz = R20 * rx + R21 * ry + R22 * rz
            lx = x + qx - Bx
            ly = y + qy - By
            lz = z + qz - Bz
            L = sqrt(lx * lx + ly * ly + lz * lz)
            lengths[i] = L
            ux, uy, uz = lx / L, ly / L, lz / L
            t = tensions[i]
            if mode:
                # bending angle (eq 6) as a magnitude; total wrap Theta = theta + theta0
                s = ux * vx + uy * vy + uz * vz
                s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
                Th = mu * (abs(asin(s)) + th0)
                # cable direction: Schmitt trigger on the length (estimation.direction)
                d, e = dirs[i], ext[i]
                if e != e:
                    e = L
                if d <= 0.0 and L > e + db:
                    d = 1.0
                    e = L
                elif d >= 0.0 and L < e - db:
                    d = -1.0
                    e = L
                elif d > 0.0:
                    if L > e:
                        e = L
                elif d < 0.0:
                    if L < e:
                        e = L
                dirs[i] = d
                ext[i] = e
                if mode < 3:
                    # physics.capstan.motor2tip: pulling (shortening or unmoved) t e^-mu Theta, else t e^mu Theta
                    t = t * exp(-Th) if d <= 0.0 else t * exp(Th)
                else:
                    dx = 0.0 if first else -(L - L_prev[i])  # motor travel, + while pulling
                    vi = vel[i]
                    vi += a_v * ((dx / dt if dt > 0 else 0.0) - vi)
                    vel[i] = vi
                    t -= b_visc * vi  # physics.friction.viscous
                    if Fc > 0.0 and not first:  # physics.friction.DahlStep
                        ad = exp(-sig * abs(dx) / Fc)
                        Fd = ad * F_dahl[i] + (1.0 if dx > 0 else (-1.0 if dx < 0 else 0.0)) * Fc * (1.0 - ad)
                        F_dahl[i] = Fd
                        t -= Fd
                    # friction state of the capstan transition (estimators.capstan_state), then t e^-phi mu Theta
                    den = Th * (t if t > 1e-6 else 1e-6)
                    ph = phi[i] + k_st * dx / (den if den > 1e-12 else 1e-12)
                    ph = 1.0 if ph > 1.0 else (-1.0 if ph < -1.0 else ph)
                    phi[i] = ph
                    t = t * exp(-ph * Th)
            # f = -A t (eq 8): column i of A is [-u; -(R r_i) x u]
            fx += t * ux
            fy += t * uy
            fz += t * uz
            mx += t * (qy * uz - qz * uy)
            my += t * (qz * ux - qx * uz)
            mz += t * (qx * uy - qy * ux)
        self.L_prev = lengths
        w = [fx, fy, fz, mx, my, mz]
        if self.turn_axes:
            self._turn(w, (x, y, z), dt)
        dt_k = self.kalman.dt if self.kalman is not None else 0.0
        kf = self.kalman
        if kf is not None:
            if kf.started:  # SteadyWrenchKalman.update, inlined: predict, innovation, steady-gain update
                kw, kwd, K0, K1 = kf.w, kf.w_dot, kf.K0, kf.K1
                for j in range(6):
                    wp = kw[j] + dt_k * kwd[j]
                    yj = w[j] - wp
                    kw[j] = wp + K0[j] * yj
                    kwd[j] += K1[j] * yj
                w = list(kw)
            else:
                w = kf.update(w)
        return lengths, w

    def _turn(self, w: list, pos: tuple, dt: float) -> None:
        """Subtract the step-3 turn corrections from w in place (estimation.turn.TurnCompensator)."""
        for k, (axis, dur, tdb, fwd, bwd) in enumerate(self.turn_axes):
            st = self.turn_state[k]
            d, e, tau = st
            p = pos[axis]
            if e != e:
                e = p
            flipped = False
            if d <= 0.0 and p > e + tdb:
                flipped, d, e = d < 0.0, 1.0, p
            elif d >= 0.0 and p < e - tdb:
                flipped, d, e = d > 0.0, -1.0, p
            elif d > 0.0:
                e = p if p > e else e
            elif d < 0.0:
                e = p if p < e else e
            tau = 0.0 if flipped else tau + dt
            st[0], st[1], st[2] = d, e, tau
            if d != 0.0 and 0.0 <= tau < dur:
                s = tau / dur
                for j, c in enumerate(fwd if d > 0 else bwd):
                    acc = c[-1]  # Horner, as numpy.polynomial.polynomial.polyval
                    for cj in c[-2::-1]:
                        acc = cj + acc * s
                    w[j] -= acc
