"""pybullet world of one pad and the end effector's tip: contact forces are the F/T ground truth.

Frame {B} of the robot (teleop.core.kinematics): the pad's top surface is the plane z = surface_z facing -z,
the pad fills z in [surface_z, surface_z + thickness], its centre on the z axis. The tip is a sphere whose
touching point is the robot's tool tip (see WorldParams.contact_radius); it is a dynamic body driven
either kinematically (a stiff fixed constraint: calibration, a rigid robot) or through a Cartesian spring
K (3, 3) [N/m] and damper C (3, 3) [N s/m] to its commanded position (a compliant cable robot).

Contacts are pybullet's soft contacts (contactStiffness / contactDamping). The stiffness of the pad under
the tip comes from the pad's material map (`Pad.stiffness_at`, footprint average) through the measured
calibration of `scenes.calibration`; it is updated when the tip moves over a different material. A pad
with a hole is built from four boxes whose inner faces form the hole: an 8 mm square, so a poke along
+-x or +-y meets one flat wall (in a round 8 mm hole a 3 mm tip pushed 2 mm sideways would touch a
polygonal approximation on three faces at once). One BulletClient per world, DIRECT mode, nothing connected at import.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import functools
import math
import os
import sys
from dataclasses import dataclass

import numpy as np

from scenes.calibration import default_calibration
from scenes.pads import Pad
from teleop.core.kernels.jit import bind
from teleop.core.kernels.sim import series_spring_force


_BANNER_SILENCED = []


def _silence_banner_at_exit() -> None:
    """pybullet writes its "pybullet build time" banner to fd 1 when the process exits (no fflush before
    reaches it; measured), which would end every piped command's output. Once pybullet is loaded, the
    last Python exit handler flushes Python's streams and points fd 1 at /dev/null."""
    if _BANNER_SILENCED:
        return
    _BANNER_SILENCED.append(True)

    def _mute():
        try:
            sys.stdout.flush()
            sys.stderr.flush()
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
        except (OSError, ValueError):
            pass

    atexit.register(_mute)


@contextlib.contextmanager
def _quiet_fds(fds: tuple = (1,)):
    """Silence C-level writes to the file descriptors `fds` (1: pybullet's connect banner; 2: its build-time
    banner on import) without touching Python's sys.stdout and sys.stderr objects."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(fd) for fd in fds]
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            for fd in fds:
                os.dup2(null.fileno(), fd)
            yield
    finally:
        try:
            ctypes.CDLL(None).fflush(None)  # push C-buffered text into /dev/null before restoring the fds
        except (OSError, AttributeError):
            pass
        for fd, copy in zip(fds, saved):
            os.dup2(copy, fd)
            os.close(copy)


N_RING = 4  # square hole: each poke direction meets one flat wall (a 16-gon let the tip touch 3 faces)
# pybullet keeps no contact point farther apart than its contact breaking threshold (1e-4 m, set in open:
# Bullet drops a manifold point beyond it and adds none); with the sphere's lowest point this far above the
# pad's top face before and after a step (every pad body lies below that face) the step has no contact point
CLEAR_GAP = 1e-3  # [m], 10x the threshold
_NO_FORCE = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class WorldParams:
    """Simulation constants (SI).

    Attributes:
        dt: physics time step [s] (1 kHz, the loop rate).
        tip_radius: radius of the flat tip [m] (sets the pad stiffness through its footprint).
        contact_radius: radius of the contact sphere standing in for the tip in pybullet [m]; larger than
            any indentation, because once the sphere's centre enters the pad Bullet's sphere-box algorithm
            adds a second contact point and the force doubles (measured). Pads with a hole use
            min(contact_radius, 0.75 hole radius).
        indenter_mass: moving mass of the end effector [kg] (a 3D-printed shaft, ~10 g).
        damping_ratio: contact damping ratio zeta; contactDamping = 2 zeta sqrt(K m) [-].
        lateral_friction: tip-silicone Coulomb friction coefficient [-].
        solver_iterations: pybullet solver iterations per step.
        surface_z: z of the pad's top surface in {B} [m] (5 mm ahead of the tip at the home pose).
    """

    dt: float = 1e-3
    tip_radius: float = 0.0015
    contact_radius: float = 0.005
    indenter_mass: float = 0.01
    damping_ratio: float = 0.5
    lateral_friction: float = 0.5
    solver_iterations: int = 20
    surface_z: float = 0.030


def implicit_spring(K, C, m: float, dt: float) -> bool:
    """True when the series spring-damper (K, C) (3, 3) on the tip mass m [kg] needs the implicit force of
    PadWorld.step at time step dt [s]: an explicit spring on the 10 g tip diverges at 1 kHz once
    sqrt(K/m) dt nears 1 (K ~ 1e4 N/m); below sqrt(K/m) dt = 0.5 (and dt C/m < 0.5) the explicit force
    is kept (it is what the palpation tests were measured with)."""
    k = float(np.abs(np.linalg.eigvalsh((np.asarray(K, float) + np.asarray(K, float).T) / 2)).max())
    c = float(np.abs(np.linalg.eigvalsh((np.asarray(C, float) + np.asarray(C, float).T) / 2)).max())
    return math.sqrt(k / m) * dt > 0.5 or dt * c / m > 0.5


class PadWorld:
    """One pad and the tip in a private pybullet client.

    Use as a context manager (`open` connects, `close` disconnects). `step(target)` advances one dt with
    the tip commanded to `target` (3,) [m] (touching point in {B}); `contact_force()` is the (3,) force of
    the pad on the tip [N]; `tip()` the tip's actual touching point [m].
    """

    def __init__(self, pad: Pad, params: WorldParams = WorldParams(), calibration=None,
                 stiffness=None, damping=None):
        self.pad = pad
        self.params = params
        self._calibration = calibration
        self.K = None if stiffness is None else np.asarray(stiffness, dtype=float).reshape(3, 3)
        self.C = None if damping is None else np.asarray(damping, dtype=float).reshape(3, 3)
        self.client = None
        self.is_open = False

    # lifecycle -------------------------------------------------------------------------------------
    def open(self) -> None:
        with _quiet_fds((1, 2)):  # the pybullet C library prints its build time on import, argv on connect
            import pybullet as pb  # heavy: loaded when a world opens (DIRECT, nothing at import)
            from pybullet_utils.bullet_client import BulletClient
        _silence_banner_at_exit()
        if self.is_open:
            return
        p = self.params
        self.calibration = self._calibration or default_calibration(p, PadWorld)
        with _quiet_fds():
            c = BulletClient(connection_mode=pb.DIRECT)
        self.client, self._pb = c, pb
        c.setTimeStep(p.dt)
        c.setGravity(0, 0, 0)
        # Bullet's default contact breaking threshold (0.02 m) is sized for metre-scale scenes; 0.1 mm suits a
        # millimetre tip. (It alone did not stop extra manifold points: see the contact sphere and no-roll.)
        c.setPhysicsEngineParameter(numSolverIterations=p.solver_iterations, deterministicOverlappingPairs=1,
                                    contactBreakingThreshold=1e-4)
        self._xy_cached = np.zeros(2)
        # a slab whose material map has regions: its stiffness under the tip follows the tip (one material
        # and thickness everywhere gives the same stiffness at every point: set once)
        self._graded = bool(self.pad.regions) and self.pad.hole_radius <= 0
        self._k_set = None
        self._build_pad()
        sph = c.createCollisionShape(pb.GEOM_SPHERE, radius=self.proxy_radius)
        start = [0.0, 0.0, p.surface_z - self.proxy_radius - 0.005]
        self.body = c.createMultiBody(p.indenter_mass, sph, basePosition=start)
        # the tip does not roll: friction torques turned the sphere and every new contact location on it
        # became an extra manifold point (measured: up to 4, four times the slope). A huge rotational
        # inertia and full angular damping keep it from turning.
        c.changeDynamics(self.body, -1, linearDamping=0.0, angularDamping=1.0, lateralFriction=p.lateral_friction,
                         localInertiaDiagonal=[1e3, 1e3, 1e3])
        if self.K is None:
            self._cid = c.createConstraint(self.body, -1, -1, -1, pb.JOINT_FIXED, [0, 0, 0], [0, 0, 0], start)
            c.changeConstraint(self._cid, start, maxForce=1e4)
        cid = c._client
        # pybullet's calls with their arguments bound by position (keywords cost more a call, and there are
        # five calls per step); the tip's own queries bind the body too
        self._tip_pos = functools.partial(pb.getBasePositionAndOrientation, self.body, cid)
        self._tip_vel = functools.partial(pb.getBaseVelocity, self.body, cid)
        self._push_tip = functools.partial(pb.applyExternalForce, self.body, -1)  # (force, position, flags, client)
        self._client_id = cid
        self._change_constraint = functools.partial(pb.changeConstraint, physicsClientId=cid)
        self._step = functools.partial(pb.stepSimulation, cid)
        self._tip_contacts = functools.partial(pb.getContactPoints, self.body, -1, -2, -2, cid)  # any body, any link
        self._world_frame = pb.WORLD_FRAME
        self._z_clear = p.surface_z - self.proxy_radius - CLEAR_GAP  # sphere centres above it touch nothing
        self._z_before = start[2]  # the sphere centre's z before the last step [m]
        if self.K is not None:
            self._implicit = implicit_spring(self.K, self.C, p.indenter_mass, p.dt)
            self._D, self._Mi, self._dtm = self.C, np.eye(3), 0.0
            if self._implicit:
                # f = -K (e + dt v') - C v', v' = v + dt/m (f + f_contact): solved for f with the contact force
                # of the last step, so the static stiffness stays K and the step is stable for any K
                D = (p.dt * self.K + self.C)
                self._Mi = np.linalg.inv(np.eye(3) + D * (p.dt / p.indenter_mass))
                self._D = D
                self._dtm = p.dt / p.indenter_mass
            self._KDM = np.ascontiguousarray(np.stack([self.K, self._D, self._Mi]))  # the kernel's matrices
        self._r = self.proxy_radius
        self._spring = self._target_ok = None  # series_spring_force bound at the first step, its checked target
        self._steps = 0  # stepSimulation calls so far; the contact force is cached per step
        self._fc, self._fc_step = None, -1
        self._pos, self._pos_step = None, -1  # the tip's base position, cached per step like the contact force
        self._vel, self._vel_step, self._dt = None, -1, p.dt  # its velocity from two positions (_velocity)
        self.is_open = True

    def close(self) -> None:
        if self.is_open:
            self.client.disconnect()
            self.client = None
            self.is_open = False

    def __enter__(self):
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # building --------------------------------------------------------------------------------------
    def _set_contact(self, body: int, k_target: float) -> None:
        K = self.calibration.pybullet_stiffness(k_target)
        D = 2.0 * self.params.damping_ratio * np.sqrt(K * self.params.indenter_mass)
        self.client.changeDynamics(body, -1, contactStiffness=K, contactDamping=D,
                                   lateralFriction=self.params.lateral_friction)

    def _build_pad(self) -> None:
        c, pb, pad, p = self.client, self._pb, self.pad, self.params
        self._home = {}
        h = pad.thickness
        zc = p.surface_z + h / 2
        self.ring = []
        self.offset = np.zeros(2)
        if pad.hole_radius > 0:
            ro, ri = pad.size / 2, pad.hole_radius
            half = [(ro - ri) / 2, ro * np.tan(np.pi / N_RING), h / 2]
            shape = c.createCollisionShape(pb.GEOM_BOX, halfExtents=half)
            k_wall = pad.wall_stiffness(p.tip_radius)
            for i in range(N_RING):
                phi = 2 * np.pi * i / N_RING
                pos = [(ro + ri) / 2 * np.cos(phi), (ro + ri) / 2 * np.sin(phi), zc]
                b = c.createMultiBody(0, shape, basePosition=pos, baseOrientation=c.getQuaternionFromEuler([0, 0, phi]))
                self._home[b] = (pos, c.getQuaternionFromEuler([0, 0, phi]))
                self._set_contact(b, k_wall)
                self.ring.append(b)
            self.slab = None
            self.pad_bodies = list(self.ring)
            return
        # a box even for round pads: pybullet's sphere-box algorithm keeps one contact point, while the
        # convex-convex sphere-cylinder manifold was measured to keep two (doubling the slope)
        shape = c.createCollisionShape(pb.GEOM_BOX, halfExtents=[pad.size / 2, pad.size / 2, h / 2])
        self.slab = c.createMultiBody(0, shape, basePosition=[0, 0, zc])
        self._home[self.slab] = ([0.0, 0.0, zc], (0.0, 0.0, 0.0, 1.0))
        self.pad_bodies = [self.slab]
        self._update_slab(np.zeros(2), force=True)

    def _update_slab(self, xy: np.ndarray, force: bool = False) -> None:
        """Set the slab's contact stiffness to the material map under the tip at xy (the caller skips
        moves under 50 um)."""
        self._xy_cached = np.array(xy, dtype=float)
        self._xc, self._yc = self._xy_cached.tolist()
        k = self.pad.stiffness_at(self._xy_cached - self.offset, self.params.tip_radius)
        if force or self._k_set is None or abs(k / self._k_set - 1.0) > 1e-3:
            self._set_contact(self.slab, k)
            self._k_set = k

    def set_offset(self, xy) -> None:
        """Place the pad with its centre at xy (2,) [m] in {B} (a positioning stage under the robot)."""
        self.offset = np.array(xy, dtype=float).reshape(2)
        self._fc_step = -1
        for b, (pos, orn) in self._home.items():
            self.client.resetBasePositionAndOrientation(b, [pos[0] + self.offset[0], pos[1] + self.offset[1], pos[2]], orn)
        if self.slab is not None:
            self._update_slab(np.asarray(self._tip_pos()[0][:2]), force=True)

    @property
    def proxy_radius(self) -> float:
        """Radius of the contact sphere [m]."""
        r = self.params.contact_radius
        return min(r, 0.75 * self.pad.hole_radius) if self.pad.hole_radius > 0 else r

    # stepping --------------------------------------------------------------------------------------
    def centre(self) -> np.ndarray:
        """(3,) sphere centre [m]."""
        return np.asarray(self.client.getBasePositionAndOrientation(self.body)[0])

    def _touching_point(self) -> np.ndarray:
        """(3,) touching point (sphere centre + r z) [m]."""
        x, y, z = self._position()
        return np.array([x, y, z + self._r])

    tip = _touching_point  # the public name (advance writes it out: a wrapper put on `tip` does not time it twice)

    def _position(self) -> tuple:
        """The sphere centre (x, y, z) [m], queried once per step (only stepping moves the tip); with the
        position of the step before, the tip's velocity of this step too (`_velocity`)."""
        if self._pos_step != self._steps:
            pos = self._tip_pos()[0]
            if self._pos_step == self._steps - 1 and self._pos is not None:
                x0, y0, z0 = self._pos
                dt = self._dt
                self._vel, self._vel_step = ((pos[0] - x0) / dt, (pos[1] - y0) / dt, (pos[2] - z0) / dt), self._steps
            self._pos, self._pos_step = pos, self._steps
        return self._pos

    def _velocity(self) -> tuple:
        """The tip's velocity (vx, vy, vz) [m/s] after the last step: Bullet integrates a multibody base's
        position semi-implicitly, x_k = x_(k-1) + dt v_k, so v_k = (x_k - x_(k-1)) / dt from the positions
        queried anyway (equal to getBaseVelocity's to round-off, 2e-15 m/s at 0.03 m/s, contact included:
        measured and tested), one pybullet query a step fewer; pybullet's own after an open or a skipped step."""
        if self._vel_step == self._steps:
            return self._vel
        return self._tip_vel()[0]

    def velocity(self) -> np.ndarray:
        return np.asarray(self._tip_vel()[0])

    def indentation(self) -> float:
        """Depth of the touching point below the pad surface [m] (negative: above it)."""
        return float(self.tip()[2] - self.params.surface_z)

    def advance(self, target, steps: int = 1) -> tuple:
        """`steps` steps toward `target` (3,) [m]; (tip (3,) [m] as `tip`, contact force (fx, fy, fz) [N] as
        `contact_force`): a robot reading's physics in one call."""
        step = self._step_to
        for _ in range(steps):
            step(target)
        x, y, z = self._position()  # _touching_point written out (this runs every reading)
        return np.array([x, y, z + self._r]), self._contact_force_tuple()

    def _step_to(self, target) -> None:
        """Advance one dt with the tip (touching point) commanded to `target` (3,) [m]."""
        pos = self._position()
        if self._graded and (abs(pos[0] - self._xc) > 5e-5 or abs(pos[1] - self._yc) > 5e-5):
            self._update_slab(np.array(pos[:2]))
        if self.K is None:
            self._change_constraint(self._cid, [float(target[0]), float(target[1]), float(target[2]) - self._r],
                                    maxForce=1e4)  # the sphere centre's target
        else:  # the series spring-damper (kernel sim.series_spring_force)
            fc = self._contact_force_tuple() if self._implicit else _NO_FORCE
            if target is not self._target_ok:  # the kernel takes a (3,) float64 contiguous array, its one type
                if type(target) is np.ndarray and target.dtype == np.float64 and target.shape == (3,) \
                        and target.flags.c_contiguous:
                    self._target_ok = target  # the caller's own array (the robot's target), checked once
                else:
                    target = np.array(target, dtype=np.float64).reshape(3)
            v = self._velocity()
            call = self._spring
            if call is None:  # bound to its argument types (jit.bind): pybullet's tuples of floats, the target array
                call = self._spring = bind(series_spring_force, pos, v, target, self._r, self._KDM, self._dtm, fc,
                                           self._implicit)
            f = call(pos, v, target, self._r, self._KDM, self._dtm, fc, self._implicit)
            self._push_tip(f, pos, self._world_frame, self._client_id)
        self._z_before = pos[2]
        self._step()
        self._steps += 1

    step = _step_to  # the public name (advance calls _step_to: a wrapper put on `step` times it once)

    def contact_force(self) -> np.ndarray:
        """(3,) force of the pad on the tip [N]: normal plus friction forces of every contact point."""
        return np.array(self._contact_force_tuple())

    def _contact_force_tuple(self) -> tuple:
        """contact_force as a tuple, summed once per step (the contact points change only when stepping); no
        query while the sphere is clear of the pad (CLEAR_GAP: pybullet would return no point)."""
        if self._fc_step == self._steps:
            return self._fc
        if self._position()[2] < self._z_clear and self._z_before < self._z_clear:
            self._fc, self._fc_step = _NO_FORCE, self._steps
            return self._fc
        fx = fy = fz = 0.0
        for cp in self._tip_contacts():
            # cp[7] normal on B pointing towards A, cp[9] its force; cp[10..13] friction magnitudes and
            # directions as applied to B (measured: a tip sliding +x reads +x), so A gets the opposite:
            # F += fn n - f1 d1 - f2 d2, written out per axis
            (n0, n1, n2), fn, f1, (a0, a1, a2), f2, (b0, b1, b2) = cp[7], cp[9], cp[10], cp[11], cp[12], cp[13]
            fx += fn * n0 - f1 * a0 - f2 * b0
            fy += fn * n1 - f1 * a1 - f2 * b1
            fz += fn * n2 - f1 * a2 - f2 * b2
        self._fc, self._fc_step = (fx, fy, fz), self._steps
        return self._fc

    def n_contacts(self) -> int:
        """Number of contact points between the tip and the pad (1 while touching, by construction)."""
        return len(self._tip_contacts())
