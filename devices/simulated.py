"""`sim://` simulated stylus: a Geomagic-Touch-like device held by a model operator.

The operator's hand and the stylus are one mass m [kg] pulled by a spring-damper (k [N/m], b [N s/m])
towards a scripted target; the commanded stylus force acts on the same mass, so the operator feels it
(pushing into a stiff pad stops the hand short of its target):

    m a = k (p_target(t) - p) - b v + F_cmd + F_tremor(t)

integrated with semi-implicit Euler at a fixed step h (so a run is deterministic for a seed whatever the
read timing); the script's time starts at open(), or at the first read() with `start_on_read` (the URL
default, so a session's script starts with its loop). Scripts: `hold`, `sine` (amplitude along an axis), `pokes` (press down by a depth and
release, periodically), `recorded` (targets from an (N, 4) array of t, x, y, z). Buttons: bit 0 deadman
(operator present), bit 1 clutch, each from a list of (t0, t1) intervals. Time comes from `clock` (default
time.perf_counter, relative to open()); tests pass a manual clock.

URL: ``sim://?script=pokes&depth_mm=8&period_s=2&seed=1&clutch=1.0-1.5&absent=3-3.2&spec=touch``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from devices.base import OMEGA_SPEC, TOUCH_SPEC, ContextDevice, DeviceError, DeviceSpec, HapticSample
from devices.guard import guarded_force
from teleop.core.errors import InputError
from teleop.core.kernels import operator as KO
from teleop.core.kernels.jit import bind
from teleop.core.kernels.operator import operator_steps, script_offset
from teleop.core.kinematics import rotation_zyx
from teleop.io.recording import read_session

SCRIPTS = ("hold", "sine", "pokes", "recorded")


@dataclass(frozen=True)
class OperatorParams:
    """Operator (hand + stylus) model.

    Attributes:
        m: moving mass of hand and stylus [kg].
        k: hand stiffness towards the target [N/m].
        b: hand damping [N s/m].
        tremor: standard deviation of the hand's random force [N] (Ornstein-Uhlenbeck, 0.05 s).
        h: integration step [s].
    """

    m: float = 0.15
    k: float = 150.0
    b: float = 6.0
    tremor: float = 0.005
    h: float = 0.001

    def __post_init__(self):
        for name in ("m", "k", "b", "h"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InputError(f"sim stylus: {name} must be > 0, got {v}")
        if not (math.isfinite(self.tremor) and self.tremor >= 0):
            raise InputError(f"sim stylus: tremor must be >= 0, got {self.tremor}")


@dataclass(frozen=True)
class Script:
    """Target trajectory of the operator's hand in the device frame [m, s].

    Attributes:
        kind: one of SCRIPTS.
        center: (3,) rest position [m].
        axis: (3,) unit direction of sine / poke motion.
        amplitude: sine amplitude, or poke depth [m].
        period: sine period or poke period [s].
        duty: fraction of a poke period spent pressed.
        points: (N, 4) rows t, x, y, z for `recorded` (linear interpolation, held at the ends).
        clutch, absent: ((t0, t1), ...) intervals with the clutch pressed / the operator's hand off.
        tilt: constant stylus tilt about x [rad] (0: aligned).
    """

    kind: str = "sine"
    center: tuple = (0.0, 0.0, 0.0)
    axis: tuple = (0.0, 0.0, -1.0)
    amplitude: float = 0.01
    period: float = 2.0
    duty: float = 0.5
    points: np.ndarray | None = None
    clutch: tuple = ()
    absent: tuple = ()
    tilt: float = 0.0

    def __post_init__(self):
        if self.kind not in SCRIPTS:
            raise InputError(f"sim stylus: script '{self.kind}' unknown (expected one of: {', '.join(SCRIPTS)})")
        if self.kind == "recorded":
            pts = np.asarray(self.points, dtype=float) if self.points is not None else np.zeros((0, 4))
            if pts.ndim != 2 or pts.shape[1] != 4 or len(pts) < 1 or not np.isfinite(pts).all():
                raise InputError("sim stylus: script 'recorded' needs points of shape (N, 4): t, x, y, z")
        if not (self.period > 0 and 0 < self.duty <= 1 and math.isfinite(self.amplitude)):
            raise InputError("sim stylus: need period > 0, 0 < duty <= 1, finite amplitude")

    def target(self, t: float) -> np.ndarray:
        """(3,) hand target at time t [s]."""
        if self.kind == "recorded":
            pts = np.asarray(self.points, dtype=float)
            return np.array([np.interp(t, pts[:, 0], pts[:, j]) for j in (1, 2, 3)])
        return np.array(self.target_xyz(t))

    def target_xyz(self, t: float) -> tuple:
        """target(t) as three floats: centre + axis s(t) (kernel operator.script_offset)."""
        if self.kind == "recorded":
            return tuple(self.target(t).tolist())
        s = script_offset(SCRIPTS.index(self.kind), float(t), float(self.amplitude), float(self.period),
                          float(self.duty))
        (cx, cy, cz), (ax, ay, az) = self.center, self.axis
        return float(cx + ax * s), float(cy + ay * s), float(cz + az * s)

    def buttons(self, t: float) -> tuple[int, bool]:
        """(button mask, operator present) at time t."""
        present = not any(t0 <= t < t1 for t0, t1 in self.absent)
        clutch = any(t0 <= t < t1 for t0, t1 in self.clutch)
        return (1 if present else 0) | (2 if clutch else 0), present


class SimulatedStylus(ContextDevice):
    """A simulated haptic stylus (HapticDevice) driven by an operator model."""

    def __init__(self, script: Script | None = None, operator: OperatorParams | None = None,
                 spec: DeviceSpec = TOUCH_SPEC, seed: int = 0, clock=None, start_on_read: bool = False):
        self.script = script or Script()
        self.operator = operator or OperatorParams()
        self.spec = spec
        self.seed = int(seed)
        self._clock = clock
        self.start_on_read = bool(start_on_read)
        self.is_open = False
        self.p = np.zeros(3)
        self.v = np.zeros(3)

    def open(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self._nbuf, self._nbuf_i = np.empty((0, 3)), 0
        self.clock = self._clock if self._clock is not None else time.perf_counter
        self.t0 = None if self.start_on_read else float(self.clock())
        self.t = 0.0
        self.steps = 0
        self.p = self.script.target(0.0).astype(float).copy()
        self.v = np.zeros(3)
        self.F_cmd = (0.0, 0.0, 0.0)  # commanded force (fx, fy, fz) [N], device frame
        self.R = rotation_zyx(0.0, 0.0, self.script.tilt)
        self._lo, self._hi = np.asarray(self.spec.workspace_min), np.asarray(self.spec.workspace_max)
        self._c_for = None  # (operator, script, spec) the integrator's constants were built for
        self._x = np.zeros(9)  # the integrator's state: p, v, F_tremor (p, v, F_tremor are copies of it)
        self._x[0:3] = self.p
        self._pv = self._x.copy()  # the state's last copy (p, v, F_tremor views of it after a step)
        self._no_targets = np.zeros((0, 3))
        self._steps_call = None  # operator_steps bound at the first step (_advance)
        self.is_open = True

    def close(self) -> None:
        self.F_cmd = (0.0, 0.0, 0.0)  # commanded force (fx, fy, fz) [N], device frame
        self.is_open = False

    def _constants(self) -> np.ndarray:
        """The integrator's constants (kernel operator.operator_steps' c), rebuilt when the operator, the
        script or the device spec was replaced (the blind-test rig swaps scripts between presses)."""
        key = self._c_for
        if key is None or key[0] is not self.operator or key[1] is not self.script or key[2] is not self.spec:
            op, sc = self.operator, self.script
            a_ou = math.exp(-op.h / 0.05)
            c = np.zeros(KO.N_CONST)
            c[[KO.H, KO.M, KO.K, KO.B, KO.A_OU, KO.S_OU, KO.KIND, KO.AMP, KO.PERIOD, KO.DUTY]] = (
                op.h, op.m, op.k, op.b, a_ou, op.tremor * math.sqrt(1.0 - a_ou * a_ou), SCRIPTS.index(sc.kind),
                sc.amplitude, sc.period, sc.duty)
            c[KO.CENTER:KO.CENTER + 3], c[KO.AXIS:KO.AXIS + 3] = sc.center, sc.axis
            c[KO.LO:KO.LO + 3], c[KO.HI:KO.HI + 3] = self._lo, self._hi
            self._c, self._absent = c, np.array(sc.absent, dtype=float).reshape(-1, 2)
            self._c_for = (self.operator, self.script, self.spec)
        return self._c

    def _advance(self, t_now: float) -> None:
        """Integrate up to t_now [s] (kernel operator.operator_steps)."""
        op = self.operator
        h = op.h
        target_steps = int(math.floor(t_now / h + 1e-6))  # integer step count: no drift from summing h
        n = target_steps - self.steps
        if n <= 0:
            return
        if n > int(1.0 / h):  # a long pause: integrate at most the last 1 s (the hand has settled anyway)
            self.steps = target_steps - int(1.0 / h)
            n = int(1.0 / h)
        tremor = op.tremor > 0
        i0 = self._nbuf_i
        if tremor and i0 + n <= len(self._nbuf):  # _noise's usual case, written out (this runs every tick)
            noise, self._nbuf_i = self._nbuf, i0 + n
        else:
            noise, i0 = self._noise(n) if tremor else (self._nbuf, 0)
        targets = self._no_targets
        if self.script.kind == "recorded":
            targets = np.array([self.script.target_xyz((self.steps + i + 1) * h) for i in range(n)])
        x = self._x
        fx, fy, fz = self.F_cmd
        c, call = self._constants(), self._steps_call
        if call is None:  # bound to its argument types (jit.bind): the stylus's own arrays, floats and ints
            call = self._steps_call = bind(operator_steps, x, fx, fy, fz, self.steps, n, c, noise, i0, tremor, targets,
                                           self._absent)
        call(x, fx, fy, fz, self.steps, n, c, noise, i0, tremor, targets, self._absent)
        self.steps += n
        # p, v (and F_tremor, when asked for): views of one fresh copy (never written in place: a sample may hand
        # them out as they are)
        self._pv = pv = x.copy()
        self.p, self.v, self.t = pv[0:3], pv[3:6], self.steps * h

    @property
    def F_tremor(self) -> np.ndarray:
        """(3,) the operator's tremor force [N] after the last step (a view of the state's copy, made when asked:
        the loop does not read it)."""
        return self._pv[6:9]

    def _noise(self, n: int) -> tuple:
        """(rows, i0): n rows of 3 standard normal draws at rows[i0:i0 + n], taken from blocks drawn 1024 rows
        at a time (the same stream whatever the read timing)."""
        if self._nbuf_i + n <= len(self._nbuf):
            i0 = self._nbuf_i
            self._nbuf_i += n
            return self._nbuf, i0
        out = [self._nbuf[self._nbuf_i:]]
        got = len(out[0])
        while got < n:
            self._nbuf, self._nbuf_i = self.rng.standard_normal((1024, 3)), 0
            take = min(n - got, 1024)
            out.append(self._nbuf[:take])
            self._nbuf_i = take
            got += take
        return np.concatenate(out), 0

    def read(self) -> HapticSample:
        if not self.is_open:
            raise DeviceError("sim stylus: read() before open()")
        if self.t0 is None:
            self.t0 = float(self.clock())
        self._advance(float(self.clock()) - self.t0)
        sc = self.script
        buttons, present = sc.buttons(self.t) if sc.absent or sc.clutch else (1, True)
        # p and v are replaced, never written, by each step: the sample takes them without a copy
        return HapticSample(self.t, self.p, self.R, self.v, buttons, present)

    def servo_cf(self, force) -> None:
        self.F_cmd = guarded_force(self, force, "sim stylus")


def _intervals(text: str, key: str) -> tuple:
    out = []
    for part in filter(None, text.split(",")):
        try:
            a, b = (float(s) for s in part.split("-"))
        except ValueError:
            raise InputError(f"sim stylus option '{key}': expected t0-t1[,t0-t1...] in seconds, got '{text}'") \
                from None
        if not b > a:
            raise InputError(f"sim stylus option '{key}': interval {part} must have t1 > t0")
        out.append((a, b))
    return tuple(out)


_OPTIONS = {"start", "script", "seed", "amp_mm", "depth_mm", "period_s", "duty", "axis", "clutch", "absent", "tilt_deg",
            "spec", "k", "m", "b", "tremor_N", "file"}


def from_url(parsed, options: dict) -> SimulatedStylus:
    """Factory for ``sim://`` (see module docstring); unknown options raise InputError."""
    unknown = set(options) - _OPTIONS - {"clock"}
    if unknown:
        raise InputError(f"sim:// stylus: unknown option(s) {', '.join(sorted(unknown))} "
                         f"(expected: {', '.join(sorted(_OPTIONS))})")

    def num(key, default):
        try:
            v = float(options.get(key, default))
        except (TypeError, ValueError):
            raise InputError(f"sim:// stylus option '{key}': expected a number, got {options.get(key)!r}") from None
        if not math.isfinite(v):
            raise InputError(f"sim:// stylus option '{key}': expected a finite number")
        return v

    for key in ("seed", "amp_mm", "depth_mm", "period_s", "duty", "tilt_deg", "k", "m", "b", "tremor_N"):
        if key in options:
            num(key, 0.0)  # every numeric option is checked, used or not
    kind = str(options.get("script", "pokes"))
    axes = {"x": (1.0, 0, 0), "y": (0, 1.0, 0), "z": (0, 0, 1.0), "-x": (-1.0, 0, 0), "-y": (0, -1.0, 0),
            "-z": (0, 0, -1.0)}
    axis = str(options.get("axis", "-z"))
    if axis not in axes:
        raise InputError(f"sim:// stylus option 'axis': expected one of {', '.join(axes)}, got '{axis}'")
    points = None
    if kind == "recorded":
        if "file" not in options:
            raise InputError("sim:// stylus script=recorded needs file=PATH (CSV t_s,x_m,y_m,z_m or a recording)")
        points = load_points(str(options["file"]))
    amp = num("depth_mm", 30.0) if kind == "pokes" else num("amp_mm", 10.0)
    script = Script(kind=kind, axis=axes[axis], amplitude=amp * 1e-3, period=num("period_s", 2.0),
                    duty=num("duty", 0.5), points=points, clutch=_intervals(str(options.get("clutch", "")), "clutch"),
                    absent=_intervals(str(options.get("absent", "")), "absent"),
                    tilt=math.radians(num("tilt_deg", 0.0)))
    op = OperatorParams(m=num("m", 0.15), k=num("k", 150.0), b=num("b", 6.0), tremor=num("tremor_N", 0.005))
    spec_name = str(options.get("spec", "touch"))
    specs = {"touch": TOUCH_SPEC, "omega": OMEGA_SPEC}
    if spec_name not in specs:
        raise InputError(f"sim:// stylus option 'spec': expected touch or omega, got '{spec_name}'")
    start = str(options.get("start", "read"))
    if start not in ("read", "open"):
        raise InputError(f"sim:// stylus option 'start': expected read or open, got '{start}'")
    return SimulatedStylus(script, op, spec=specs[spec_name], seed=int(num("seed", 0)), clock=options.get("clock"),
                           start_on_read=start == "read")


def load_points(path: str) -> np.ndarray:
    """(N, 4) t, x, y, z [s, m] from a CSV (header t_s,x_m,y_m,z_m) or a session recording's stylus track."""
    if path.endswith(".mcap"):
        s = read_session(path)
        rows = [(m["t"], *m["measured_cp"]) for m in s.messages("/stylus")]
        if not rows:
            raise InputError(f"{path}: recording has no /stylus messages")
        return np.array(rows, dtype=float)
    try:
        data = np.genfromtxt(path, delimiter=",", names=True)
    except OSError:
        raise InputError(f"{path}: file not found") from None
    names = data.dtype.names or ()
    need = ("t_s", "x_m", "y_m", "z_m")
    if any(n not in names for n in need):
        raise InputError(f"{path}: expected CSV columns {', '.join(need)}, got {', '.join(names)}")
    pts = np.column_stack([np.atleast_1d(data[n]) for n in need])
    if not np.isfinite(pts).all():
        raise InputError(f"{path}: non-numeric or missing values in t_s,x_m,y_m,z_m")
    return pts
