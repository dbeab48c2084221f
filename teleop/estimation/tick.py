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
The rotated platform anchors R r_i are cached per orientation (the loop holds the orientation, so R is
built once). A non-finite input propagates to a renderer fault (zero force); call `reset()` after a fault.

`LoopTick` is the whole device-excluded tick the loop runs: stylus position -> mapping -> lengths -> FSR
counts -> tensions -> this estimate -> rendered force (`teleop bench tick` times `LoopTick.compute`).
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
        # the per-tick constants in one tuple each (one attribute load, not ten)
        self._consts = (*self.v, self.mu, self.theta0, self.db, self.mode)
        self._dyn_consts = tuple(float(v) for v in (dynamic.b, dynamic.dahl_Fc, dynamic.dahl_sigma,
                                                    dynamic.v_smooth, dynamic.capstan_k))
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
        self._orient_key, self._orient_cache = None, None
        if self.kalman is not None:
            self.kalman.reset()
        self.renderer.reset()

    def compute(self, pose, tensions, dt: float, velocity=(0.0, 0.0, 0.0)):
        """(lengths [6], wrench [6], force (3,)) for one tick; see the module docstring."""
        lengths, w = self.estimate(pose, tensions, dt)
        return lengths, w, self.renderer.render_xyz(w[0], w[1], w[2], dt, *velocity)

    def _orient(self, a: float, b: float, g: float) -> list:
        """Per cable (R r_i - B_i, R r_i) as 6 floats for orientation (a, b, g) [rad], cached (the loop holds
        the orientation, so R is built once, not every tick)."""
        if self._orient_key == (a, b, g):
            return self._orient_cache
        sin, cos = math.sin, math.cos
        # R = Rz(a) Ry(b) Rx(g) (eq 5)
        ca, sa, cb, sb, cg, sg = cos(a), sin(a), cos(b), sin(b), cos(g), sin(g)
        R00, R01, R02 = ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg
        R10, R11, R12 = sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg
        R20, R21, R22 = -sb, cb * sg, cb * cg
        out = []
        for rx, ry, rz, Bx, By, Bz in self.cables:
            qx = R00 * rx + R01 * ry + R02 * rz
            qy = R10 * rx + R11 * ry + R12 * rz
            qz = R20 * rx + R21 * ry + R22 * rz
            out.append((qx - Bx, qy - By, qz - Bz, qx, qy, qz))
        self._orient_key, self._orient_cache = (a, b, g), out
        return out

    def estimate(self, pose, tensions, dt: float):
        """(lengths [6], wrench [6]): the tick without the renderer."""
        if isinstance(pose, np.ndarray):
            pose = pose.tolist()
        if isinstance(tensions, np.ndarray):
            tensions = tensions.tolist()
        x, y, z, a, b, g = pose
        cab = self._orient_cache if self._orient_key == (a, b, g) else self._orient(a, b, g)
        sqrt, exp, asin = math.sqrt, math.exp, math.asin
        vx, vy, vz, mu, th0, db, mode = self._consts
        dirs, ext = self.dir, self.ext
        L_prev = self.L_prev
        first = L_prev is None
        lengths = [0.0] * 6
        fx = fy = fz = mx = my = mz = 0.0
        if mode == 3:
            b_visc, Fc, sig, v_smooth, k_st = self._dyn_consts
            dahl = Fc > 0.0 and not first
            a_v = dt / (v_smooth + dt) if dt > 0 else 0.0
            inv_dt = 1.0 / dt if dt > 0 else 0.0
            vel, F_dahl, phi = self.vel, self.F_dahl, self.phi
        for i in range(6):
            # cable vector l_i = p + R r_i - B_i (eq 4-5), length, unit vector
            cx, cy, cz, qx, qy, qz = cab[i]
            lx = x + cx
            ly = y + cy
            lz = z + cz
            L = sqrt(lx * lx + ly * ly + lz * lz)
            lengths[i] = L
            ux, uy, uz = lx / L, ly / L, lz / L
            t = tensions[i]
            if mode:
                # bending angle (eq 6) as a magnitude; total wrap Theta = theta + theta0
                s = ux * vx + uy * vy + uz * vz
                s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
                Th = mu * (abs(asin(s)) + th0)
                if mode < 3:
                    # cable direction: Schmitt trigger on the length (estimation.direction); `dynamic` has no
                    # direction rule (its capstan state follows the travel), so it skips this
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
                    # physics.capstan.motor2tip: pulling (shortening or unmoved) t e^-mu Theta, else t e^mu Theta
                    t = t * exp(-Th) if d <= 0.0 else t * exp(Th)
                else:
                    dx = 0.0 if first else L_prev[i] - L  # motor travel, + while pulling
                    vi = vel[i]
                    vi += a_v * (dx * inv_dt - vi)
                    vel[i] = vi
                    t -= b_visc * vi  # physics.friction.viscous
                    if dahl:  # physics.friction.DahlStep
                        ad = exp(-sig * abs(dx) / Fc)
                        Fd = ad * F_dahl[i] + (Fc if dx > 0 else (-Fc if dx < 0 else 0.0)) * (1.0 - ad)
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
        kf = self.kalman
        if kf is not None:
            if kf.started:  # SteadyWrenchKalman.update, inlined: predict, innovation, steady-gain update
                dt_k, kw, kwd, K0, K1 = kf.dt, kf.w, kf.w_dot, kf.K0, kf.K1
                for j in range(6):
                    wp = kw[j] + dt_k * kwd[j]
                    yj = w[j] - wp
                    kw[j] = wp + K0[j] * yj
                    kwd[j] += K1[j] * yj
                w = kw[:]
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


class LoopTick:
    """The whole device-excluded tick the loop runs, on plain floats: stylus position -> mapping (motion
    scale, workspace clip, v_max step limit; teleop.mapping.Follower) -> cable lengths (inverse kinematics)
    -> FSR counts -> tensions -> estimation with the Kalman filter (ReadingEstimator.update_floats) ->
    rendered stylus force (Renderer.render_xyz).

    teleop.loop.core.Teleop calls `map`, `estimate` and `render` at its MAP, ESTIMATE and RENDER stages
    (the robot I/O sits between them); `compute` runs the three back to back for `teleop bench tick`, so the
    benchmark times the code the loop runs.

        lt = LoopTick(geom, MappingParams(), ReadingEstimator(geom, "dynamic"), Renderer(rp), cmd_dt=1e-3)
        lt.engage(p_stylus)                                  # anchors (the loop's ENABLED entry)
        L, t, w, F = lt.compute(p_stylus, v_stylus, counts, dt)

    Inputs are what the devices give: stylus position (3,) [m] and velocity (3,) [m/s] in the device frame,
    raw FSR counts (6,), as numpy arrays. Outputs: commanded lengths L [m] (the robot command; the loop makes
    the device's array), tensions [N] and wrench [N, N m] in {B} as lists of 6 floats, force (3,) tuple [N]
    in the device frame.
    """

    def __init__(self, geom: Geometry, mapping, estimator, renderer: Renderer | None = None, cmd_dt: float = 1e-3):
        from teleop.mapping import Follower

        self.follower = Follower(mapping, geom, cmd_dt)
        self.home = [float(v) for v in mapping.home]
        self.estimator = estimator
        self.renderer = renderer if renderer is not None else Renderer()
        self._home_mapping()  # the estimator and renderer keep their state (the loop may hand in its own)

    def _home_mapping(self) -> None:
        # compute()'s own mapping state; the loop keeps its own (Teleop.pose, L_last, anchors) and calls map()
        self.pos = self.home[:3]
        self.anchor_stylus = [0.0, 0.0, 0.0]
        self.anchor_robot = self.home[:3]
        self.L_last = None

    def reset(self) -> None:
        """Back at home, not engaged; estimator and renderer reset."""
        self._home_mapping()
        self.estimator.reset()
        self.renderer.reset()

    def engage(self, p_stylus) -> None:
        """Anchor the incremental mapping at the stylus position (3,) [m] and the current robot target."""
        self.anchor_stylus = [float(v) for v in p_stylus]
        self.anchor_robot = list(self.pos)
        if self.L_last is None:
            self.L_last = self.follower.lengths(*self.pos)

    def map(self, p_stylus, anchor_stylus, anchor_robot, pos, L_prev) -> tuple[list, list]:
        """(target position [3] [m], lengths [6] [m]): `Follower.step` (all arguments lists of floats)."""
        return self.follower.step(p_stylus, anchor_stylus, anchor_robot, pos, L_prev)

    def estimate(self, counts: list, pose: list, dt: float) -> tuple[list, list]:
        """(tensions [6] [N], wrench [6] [N, N m]) from raw FSR counts at the commanded pose [6] (lists)."""
        return self.estimator.update_floats(counts, pose, dt)

    def render(self, fx: float, fy: float, fz: float, dt: float, vx: float, vy: float, vz: float) -> tuple:
        """Stylus force (3,) [N] from the force part of the wrench and the stylus velocity (Renderer.render_xyz)."""
        return self.renderer.render_xyz(fx, fy, fz, dt, vx, vy, vz)

    def compute(self, p_stylus, v_stylus, counts, dt: float):
        """One full tick (see the class docstring): (L [6], tensions [6], wrench [6], force (3,))."""
        pos, L = self.follower.step(p_stylus.tolist(), self.anchor_stylus, self.anchor_robot, self.pos,
                                    self.L_last)
        self.pos, self.L_last = pos, L
        h = self.home
        t, w = self.estimator.update_floats(counts.tolist(), [pos[0], pos[1], pos[2], h[3], h[4], h[5]], dt)
        vx, vy, vz = v_stylus.tolist()
        return L, t, w, self.renderer.render_xyz(w[0], w[1], w[2], dt, vx, vy, vz)
