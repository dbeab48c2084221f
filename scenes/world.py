"""pybullet world of one pad and the end effector's tip: contact forces are the F/T ground truth.

Frame {B} of the robot (teleop.kinematics): the pad's top surface is the plane z = surface_z facing -z,
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

import contextlib
import ctypes
import os
import sys
from dataclasses import dataclass

import numpy as np

from scenes.pads import Pad


@contextlib.contextmanager
def _quiet_stdout():
    """Silence C-level writes to fd 1 (pybullet's connect banner) without touching Python's sys.stdout."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        try:
            ctypes.CDLL(None).fflush(None)  # push C-buffered text into /dev/null before restoring fd 1
        except (OSError, AttributeError):
            pass
        os.dup2(saved, 1)
        os.close(saved)


N_RING = 4  # square hole: each poke direction meets one flat wall (a 16-gon let the tip touch 3 faces)


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
        with _quiet_stdout():  # the pybullet C library prints its build time on import, argv on connect
            import pybullet as pb
            from pybullet_utils.bullet_client import BulletClient

        from scenes.calibration import default_calibration

        if self.is_open:
            return
        p = self.params
        self.calibration = self._calibration or default_calibration(p)
        with _quiet_stdout():
            c = BulletClient(connection_mode=pb.DIRECT)
        self.client, self._pb = c, pb
        c.setTimeStep(p.dt)
        c.setGravity(0, 0, 0)
        # Bullet's default contact breaking threshold (0.02 m) is tuned for metre-scale scenes: a tip moving a
        # few mm keeps stale manifold points and doubles the force (measured); 0.1 mm keeps one point.
        c.setPhysicsEngineParameter(numSolverIterations=p.solver_iterations, deterministicOverlappingPairs=1,
                                    contactBreakingThreshold=1e-4)
        self._build_pad()
        sph = c.createCollisionShape(pb.GEOM_SPHERE, radius=self.proxy_radius)
        start = [0.0, 0.0, p.surface_z - self.proxy_radius - 0.005]
        self.body = c.createMultiBody(p.indenter_mass, sph, basePosition=start)
        c.changeDynamics(self.body, -1, linearDamping=0.0, angularDamping=0.0, lateralFriction=p.lateral_friction)
        self._target = np.array([0.0, 0.0, p.surface_z - 0.005])
        if self.K is None:
            self._cid = c.createConstraint(self.body, -1, -1, -1, pb.JOINT_FIXED, [0, 0, 0], [0, 0, 0], start)
            c.changeConstraint(self._cid, start, maxForce=1e4)
        self._xy_cached = None
        self._k_set = None
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
        h = pad.thickness
        zc = p.surface_z + h / 2
        self.ring = []
        if pad.hole_radius > 0:
            ro, ri = pad.size / 2, pad.hole_radius
            half = [(ro - ri) / 2, ro * np.tan(np.pi / N_RING), h / 2]
            shape = c.createCollisionShape(pb.GEOM_BOX, halfExtents=half)
            k_wall = pad.wall_stiffness(p.tip_radius)
            for i in range(N_RING):
                phi = 2 * np.pi * i / N_RING
                pos = [(ro + ri) / 2 * np.cos(phi), (ro + ri) / 2 * np.sin(phi), zc]
                b = c.createMultiBody(0, shape, basePosition=pos, baseOrientation=c.getQuaternionFromEuler([0, 0, phi]))
                self._set_contact(b, k_wall)
                self.ring.append(b)
            self.slab = None
            self.pad_bodies = list(self.ring)
            return
        # a box even for round pads: pybullet's sphere-box algorithm keeps one contact point, while the
        # convex-convex sphere-cylinder manifold was measured to keep two (doubling the slope)
        shape = c.createCollisionShape(pb.GEOM_BOX, halfExtents=[pad.size / 2, pad.size / 2, h / 2])
        self.slab = c.createMultiBody(0, shape, basePosition=[0, 0, zc])
        self.pad_bodies = [self.slab]
        self._update_slab(np.zeros(2), force=True)

    def _update_slab(self, xy: np.ndarray, force: bool = False) -> None:
        """Set the slab's contact stiffness to the material map under the tip at xy (cached)."""
        if not force and self._xy_cached is not None and np.abs(xy - self._xy_cached).max() < 2e-5:
            return
        self._xy_cached = xy.copy()
        k = self.pad.stiffness_at(xy, self.params.tip_radius)
        if force or self._k_set is None or abs(k / self._k_set - 1.0) > 1e-3:
            self._set_contact(self.slab, k)
            self._k_set = k

    @property
    def proxy_radius(self) -> float:
        """Radius of the contact sphere [m]."""
        r = self.params.contact_radius
        return min(r, 0.75 * self.pad.hole_radius) if self.pad.hole_radius > 0 else r

    # stepping --------------------------------------------------------------------------------------
    def centre(self) -> np.ndarray:
        """(3,) sphere centre [m]."""
        return np.asarray(self.client.getBasePositionAndOrientation(self.body)[0])

    def tip(self) -> np.ndarray:
        """(3,) touching point (sphere centre + r z) [m]."""
        return self.centre() + np.array([0.0, 0.0, self.proxy_radius])

    def velocity(self) -> np.ndarray:
        return np.asarray(self.client.getBaseVelocity(self.body)[0])

    def indentation(self) -> float:
        """Depth of the touching point below the pad surface [m] (negative: above it)."""
        return float(self.tip()[2] - self.params.surface_z)

    def step(self, target) -> None:
        """Advance one dt with the tip (touching point) commanded to `target` (3,) [m]."""
        target = np.asarray(target, dtype=float)
        centre_target = target - np.array([0.0, 0.0, self.proxy_radius])
        c = self.client
        pos, _ = c.getBasePositionAndOrientation(self.body)
        pos = np.asarray(pos)
        if self.slab is not None:
            self._update_slab(pos[:2])
        if self.K is None:
            c.changeConstraint(self._cid, centre_target.tolist(), maxForce=1e4)
        else:
            v = np.asarray(c.getBaseVelocity(self.body)[0])
            f = -self.K @ (pos - centre_target) - self.C @ v  # spring-damper of the cable robot
            c.applyExternalForce(self.body, -1, f.tolist(), pos.tolist(), self._pb.WORLD_FRAME)
        # the tip does not roll: friction torques would turn the sphere and every new contact location
        # on it became an extra manifold point (measured: up to 4, four times the slope)
        c.resetBasePositionAndOrientation(self.body, pos.tolist(), (0.0, 0.0, 0.0, 1.0))
        c.resetBaseVelocity(self.body, angularVelocity=[0, 0, 0])
        c.stepSimulation()
        self._target = target

    def contact_force(self) -> np.ndarray:
        """(3,) force of the pad on the tip [N]: normal plus friction forces of every contact point."""
        F = np.zeros(3)
        for cp in self.client.getContactPoints(bodyA=self.body):
            # cp[7] normal on B pointing towards A, cp[9] its force; cp[10..13] friction magnitudes and
            # directions as applied to B (measured: a tip sliding +x reads +x), so A gets the opposite
            F += cp[9] * np.asarray(cp[7]) - cp[10] * np.asarray(cp[11]) - cp[12] * np.asarray(cp[13])
        return F
