"""The master-slave tick: READ -> MAP -> ROBOT I/O -> ESTIMATE -> RENDER -> WRITE -> RECORD.

The compute of MAP, ESTIMATE and RENDER is teleop.core.estimation.tick.LoopTick's `map`, `estimate` and `render`:
the code `teleop bench tick` times as one full tick (`LoopTick.compute`, the three back to back); this module adds
the device I/O, the state machine, the safety monitors and the numpy arrays the devices and the recorder take.
A robot's read() may return None while no telemetry frame has arrived yet (counted as missing telemetry).
`Teleop.tick(now)` runs one tick at host time `now` [s]; it never sleeps and never reads a clock for its
computation (the runner paces it; a replay feeds recorded times), so a session replays bit for bit. Any
exception at any stage becomes a latched FAULT with the stage and reason; the stylus force is zero in the
same tick.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from teleop.core.estimation.kalman import KalmanNoise
from teleop.core.estimation.reading import ReadingEstimator
from teleop.core.estimation.tick import LoopTick
from teleop.core.geometry import Geometry, default_geometry
from teleop.loop.warm import warm_up
from teleop.core.kinematics import lengths2pose
from teleop.loop.params import LoopParams
from teleop.loop.safety import Freshness, StuckCable, TensionRange, is_finite_reading, is_finite_sample, \
    tension_monitors
from teleop.loop.states import BEHAVIOURS, State
from teleop.core.mapping import platform_offsets, position2lengths
from teleop.core.rendering import Renderer, engage_count
from teleop.core.robot_status import RobotStatus, stop_reason

STAGES = ("read", "map", "robot", "estimate", "render", "write", "record")
HOMED, WATCHDOG_STOP, STOPPED = RobotStatus.HOMED, RobotStatus.WATCHDOG_STOP, RobotStatus.STOPPED
_STOP_BITS, _HOMED = int(WATCHDOG_STOP | STOPPED), int(HOMED)  # plain ints: IntFlag arithmetic costs us per tick
# the states as module globals: a member looked up on its enum class costs ~0.17 us (Python 3.11), the tick
# compares with them about nine times
_DISABLED, _ALIGNING, _ENABLED, _FAULT = State.DISABLED, State.ALIGNING, State.ENABLED, State.FAULT


@dataclass
class TickData:
    """What one tick saw and decided (overwritten every tick)."""

    k: int = 0
    now: float = 0.0
    sample: object = None
    reading: object = None
    robot_due: bool = False
    L_cmd: np.ndarray | None = None
    dL: np.ndarray = field(default_factory=lambda: np.zeros(6))
    F_raw: tuple = (0.0, 0.0, 0.0)  # mapped force before ramp-in, passivity and clamp [N] (device frame)
    F: np.ndarray = field(default_factory=lambda: np.zeros(3))  # stylus force commanded this tick [N]
    ramp: float = 0.0  # the Renderer's ramp-in gain (0 while it is disabled)


@dataclass(frozen=True)
class Event:
    """A state change: tick index, host time [s], states and the reason."""

    k: int
    t: float
    src: str
    dst: str
    reason: str


class Teleop:
    """State of one teleoperation session; the math is delegated to teleop.core.mapping, the estimator and a
    teleop.core.rendering.Renderer (frame map, scale, -z zeroing, ramp-in, passivity, clamp to the device's
    continuous limit). The state machine decides WHEN force may engage: the Renderer is enabled (engage_ticks
    0, it ramps in at once) on entering ENABLED and disabled on leaving it.

    Args:
        haptic: HapticDevice (opened by the caller).
        robot: Robot (opened by the caller).
        params: LoopParams.
        geom: CDPR geometry (default_geometry()).
        estimator: readings -> (tensions, wrench); default ReadingEstimator(geom, "dynamic").
        on_event: callback(Event) for state changes (the recorder's event channel).
    """

    def __init__(self, haptic, robot, params: LoopParams | None = None, geom: Geometry | None = None,
                 estimator=None, on_event=None):
        self.haptic, self.robot = haptic, robot
        self.params = params or LoopParams()
        self.geom = geom or default_geometry()
        if estimator is None:
            # the Kalman gain is designed for the period the estimator runs at: one robot frame
            estimator = ReadingEstimator(self.geom, "dynamic", kalman=KalmanNoise.for_loop(self.params))
        self.estimator = estimator
        warm_up(self.geom)  # compile or load the kernels now: no tick may pay for it (once per process)
        self.on_event = on_event
        p, m = self.params, self.params.mapping
        self.renderer = Renderer(replace(p.render, max_force=float(haptic.spec.max_force_continuous),
                                         engage_ticks=0))
        self.offsets = platform_offsets(self.geom, m.home[3:])
        # the compiled path (mapping, FSR counts -> tensions -> estimate with Kalman, render); estimators
        # without `update_arrays` (e.g. test fakes) go through their numpy `update`
        self.fast = LoopTick(self.geom, m, estimator, self.renderer, cmd_dt=p.dt * p.robot_every)
        self.fast_estimate = callable(getattr(estimator, "update_arrays", None))
        self.stylus_fresh = Freshness("stylus", p.stale_limit, p.startup_timeout)
        self.robot_fresh = Freshness("robot", p.stale_limit, p.startup_timeout)
        self.range = TensionRange(p.tension_max, p.tension_slack, p.tension_window, len(self.geom.B))
        self.stuck = StuckCable(p.stuck_window, p.stuck_rise, p.payout_eps, len(self.geom.B))
        self.x = TickData()
        self.events: list[Event] = []
        self.stage_ns = np.zeros(len(STAGES), dtype=np.int64)
        self.k = 0
        self.fault_reason = ""
        self.state = State.DISABLED
        self.behaviour = BEHAVIOURS[State.DISABLED]
        self.enable_requested = False
        self.reset_requested = False
        self.small_force_ticks = 0
        self.boot_id = None
        self.robot_status = 0
        self.pose = m.home.astype(float).copy()
        self.L_last = None  # last commanded lengths [m]
        self.tensions = np.zeros(len(self.geom.B))
        # friction-compensated tip-side tensions [N] of the last estimate (0: none yet): a view of the
        # estimator's own buffer, which each estimate overwrites (no per-tick copy)
        comp = getattr(estimator, "compensated", None)
        self.compensated = comp if comp is not None else np.zeros(len(self.geom.B))
        self.wrench = np.zeros(6)
        self._map_anchor = np.zeros(6)  # the mapping kernel's anchors [m]: stylus (3,), then robot (3,)
        self._map_anchor[3:] = self.pose[:3]
        # views of it, written in place (the kernel reads them where they are)
        self.anchor_stylus, self.anchor_robot = self._map_anchor[:3], self._map_anchor[3:]
        self.tap = None
        self.last_reading = None
        self._est_seq = None  # sequence number and robot time of the last frame the estimator saw
        self._est_t = 0.0
        self.lateness_ns = 0  # set by the runner before each tick (recorded)
        self.prev_tick_ns = 0

    # ---- operator commands -------------------------------------------------------------------------------
    def start(self, now: float) -> None:
        """Power-on: DISABLED, zero force, no motion command; watchdogs armed from `now`."""
        self.stylus_fresh.reset(now)
        self.robot_fresh.reset(now)
        if self.params.auto_enable:
            self.enable_requested = True

    def request_enable(self) -> None:
        self.enable_requested = True

    def request_disable(self) -> None:
        self.enable_requested = False

    def operator_reset(self) -> None:
        """Leave FAULT (to DISABLED) on the next tick; teleoperation needs a new enable request."""
        self.reset_requested = True

    # ---- helpers used by the states ------------------------------------------------------------------------
    @property
    def robot_homed(self) -> bool:
        return bool(self.robot_status & _HOMED)

    def telemetry_fresh(self, now: float) -> bool:
        return self.robot_fresh.is_fresh(now) and self.stylus_fresh.is_fresh(now)

    def anchor(self, now: float) -> None:
        """Engage: stylus and robot anchors for the incremental mapping (the Renderer ramps the force in)."""
        self.anchor_stylus[:] = self.x.sample.measured_cp
        self.anchor_robot[:] = self.pose[:3]
        if self.L_last is None:  # first engagement: start from where the robot is
            r = self.x.reading if self.x.reading is not None else self.last_reading
            L = None if r is None else np.asarray(r.commanded_lengths, dtype=float)
            if L is not None and np.isfinite(L).all() and (L > 0).all():
                if np.max(np.abs(L - position2lengths(self.pose[:3], self.offsets))) > 1e-4:
                    self.pose = lengths2pose(L, self.geom, guess=self.pose)
                    self.pose[3:] = self.params.mapping.home[3:]  # the mapping holds the home orientation
                    self.anchor_robot[:] = self.pose[:3]
                self.L_last = L
            else:
                self.L_last = position2lengths(self.pose[:3], self.offsets)

    def follow(self, x) -> np.ndarray:
        """ENABLED: stylus -> target -> lengths, step-limited to v_max dt and clipped to the length limits.

        teleop.core.mapping.Follower.step_into (kernel mapping.follow_step, built from the kernels that
        teleop.core.mapping.stylus2target / position2lengths / limit_lengths call; this runs every tick).
        """
        # the anchors where anchor() wrote them; the pose's position, a view: the kernel reads the previous
        # target there and writes the new one
        return self.fast.map(x.sample.measured_cp, self._map_anchor, self.pose[:3], self.L_last)

    def stop_robot(self) -> None:
        try:
            self.robot.stop()
        except Exception as exc:  # noqa: BLE001 - the fault is already being handled; note it and go on
            self._log(self.state.name, "FAULT", f"robot.stop() failed: {type(exc).__name__}: {exc}")

    # ---- state changes ---------------------------------------------------------------------------------------
    def _log(self, src: str, dst: str, reason: str) -> None:
        ev = Event(self.k, self.x.now, src, dst, reason)
        self.events.append(ev)
        if self.on_event is not None:
            try:
                self.on_event(ev)
            except Exception:  # noqa: BLE001 - a recorder failure must never break the safety path
                pass

    def _goto(self, state: State, reason: str) -> None:
        if state == self.state:
            return
        src = self.state
        self.state = state
        self.behaviour = BEHAVIOURS[state]
        if state == State.ENABLED:
            self.renderer.enable()
        else:
            self.renderer.disable()
        self._log(src.name, state.name, reason)
        if state == State.DISABLED:
            self.reset_requested = False
        self.behaviour.enter(self, self.x.now)

    def fault(self, reason: str) -> None:
        """Enter FAULT (latched) with `reason`; zero force this tick, robot stopped."""
        if self.state == State.FAULT:
            return
        self.fault_reason = reason
        self.x.L_cmd = None
        self.x.F = np.zeros(3)
        self._goto(State.FAULT, reason)

    def _reset_from_fault(self) -> None:
        self.fault_reason = ""
        self.enable_requested = False
        self.renderer.reset()
        self.boot_id = None
        self.L_last = None
        self.range.reset()
        self.stuck.reset()
        self.estimator.reset()
        self._est_seq = None
        self.robot_fresh.reset(self.x.now)
        self.stylus_fresh.reset(self.x.now)

    # ---- the tick ----------------------------------------------------------------------------------------------
    def tick(self, now: float) -> TickData:
        """One loop iteration at host time `now` [s]."""
        x, p, ns = self.x, self.params, time.perf_counter_ns
        x.k, x.now = self.k, now
        x.robot_due = self.k % p.robot_every == 0
        x.L_cmd, x.reading = None, None
        t0 = ns()
        # READ ------------------------------------------------------------------------------------------------
        try:
            x.sample = self.haptic.read()
            if not is_finite_sample(x.sample):
                raise ValueError("stylus sample has non-finite values")
            self.stylus_fresh.update(now, x.sample.t)
        except Exception as exc:  # noqa: BLE001 - every stage failure is a FAULT
            x.sample = None
            self.fault(f"read: {type(exc).__name__}: {exc}")
        if self.state == _FAULT and self.reset_requested:
            self._reset_from_fault()
        if x.sample is not None or self.state == _FAULT:
            nxt = self.behaviour.transition(self, x)
            if nxt is not None:
                self._goto(nxt, "operator reset" if self.state == _FAULT else "")
        t1 = ns()
        # MAP -------------------------------------------------------------------------------------------------
        if x.robot_due and self.state == _ENABLED:
            try:
                L = self.behaviour.command(self, x)
                if L is not None:
                    x.dL = L - self.L_last
                    x.L_cmd = L
            except Exception as exc:  # noqa: BLE001
                self.fault(f"map: {type(exc).__name__}: {exc}")
        elif x.robot_due:
            x.dL[:] = 0.0
        t2 = ns()
        # ROBOT I/O -------------------------------------------------------------------------------------------
        if x.robot_due:
            try:
                if x.L_cmd is not None and self.state == _ENABLED:
                    self.robot.command_lengths(x.L_cmd)
                    self.L_last = x.L_cmd
                x.reading = self.robot.read()
            except Exception as exc:  # noqa: BLE001
                x.reading = None
                self.fault(f"robot: {type(exc).__name__}: {exc}")
        t3 = ns()
        # ESTIMATE + watchdogs ----------------------------------------------------------------------------------
        try:
            r = x.reading
            if r is not None:
                if not is_finite_reading(r):
                    raise ValueError("robot reading has non-finite values")
                self.last_reading = r
                self.robot_status = int(r.status)
                if self.boot_id is None:
                    self.boot_id = r.boot_id
                elif r.boot_id != self.boot_id and self.state != _FAULT:
                    self.robot_status &= ~_HOMED
                    self.fault(f"firmware reset: boot id {self.boot_id} -> {r.boot_id}; re-home before motion")
                if self.robot_status & _STOP_BITS and self.state != _FAULT:
                    self.fault(f"robot status 0x{int(r.status):02x}: {stop_reason(r.status)}")
                self.robot_fresh.update(now, r.seq)
                if r.seq != self._est_seq:  # a new frame: estimate (a repeated frame changes nothing)
                    dt = r.t - self._est_t if self._est_seq is not None and r.t > self._est_t else \
                        p.dt * p.robot_every
                    self._est_seq, self._est_t = r.seq, r.t
                    if self.fast_estimate:
                        t, f = self.fast.estimate(r.fsr_counts, self.pose, dt)  # converts the counts; copies
                    else:
                        t, f = self.estimator.update(r, self.pose, dt)
                        if not (np.isfinite(t).all() and np.isfinite(f).all()):
                            raise ValueError("estimated tensions/wrench not finite")
                    self.tensions, self.wrench = t, f
                    if self.state != _FAULT:
                        reason = tension_monitors(self.range, self.stuck, now, t, x.dL, self.state != _DISABLED)
                        if reason:
                            self.fault(reason)
            if self.state != _FAULT:
                reason = self.robot_fresh.check(now) or self.stylus_fresh.check(now)
                if reason:
                    self.fault(reason)
        except Exception as exc:  # noqa: BLE001
            self.fault(f"estimate: {type(exc).__name__}: {exc}")
        t4 = ns()
        # RENDER ------------------------------------------------------------------------------------------------
        try:
            rd = self.renderer
            fx, fy, fz = self.wrench[:3].tolist()
            vx, vy, vz = x.sample.measured_cv.tolist() if x.sample is not None else (0.0, 0.0, 0.0)
            # Renderer.render_tick (zero force unless ENABLED) and its mapped force, ramp and fault in one call;
            # mapped: device frame, scaled, -z zeroed, the force that would be rendered
            x.F, x.F_raw, x.ramp, tripped = self.fast.render(fx, fy, fz, p.dt, vx, vy, vz)
            if tripped:
                self.fault(f"render: {rd.fault_reason}")
            if self.state == _ALIGNING:  # the engage rule, counted on the force that would be rendered
                self.small_force_ticks = engage_count(self.small_force_ticks, *x.F_raw, p.render.engage_N)
        except Exception as exc:  # noqa: BLE001
            x.F = np.zeros(3)
            self.fault(f"render: {type(exc).__name__}: {exc}")
        if self.state == _FAULT:
            x.F = np.zeros(3)
        t5 = ns()
        # WRITE -------------------------------------------------------------------------------------------------
        try:
            self.haptic.servo_cf(x.F)
        except Exception as exc:  # noqa: BLE001
            self.fault(f"write: {type(exc).__name__}: {exc}")
            try:
                self.haptic.servo_cf(np.zeros(3))
            except Exception:  # noqa: BLE001 - already in FAULT; the device's own watchdog takes over
                pass
        t6 = ns()
        st = self.stage_ns  # this tick's stages before the tap records them (record_us: the previous tick's)
        st[0], st[1], st[2], st[3], st[4], st[5] = t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5
        # RECORD ------------------------------------------------------------------------------------------------
        if self.tap is not None:
            try:
                self.tap(self)
            except Exception as exc:  # noqa: BLE001
                self.fault(f"record: {type(exc).__name__}: {exc}")
                try:
                    self.haptic.servo_cf(np.zeros(3))
                except Exception:  # noqa: BLE001
                    pass
        st[6] = ns() - t6
        self.k += 1
        return x

