"""Device wrappers (Gymnasium style: behaviour added around a device, not flags inside it).

- `ProcessRobot`: runs any Robot (built in the child by a factory the wiring passes) in its own process at its
  own rate; the loop exchanges the latest command and the latest reading through shared memory (a seqlock), so
  a slow robot link or a physics step never stalls the haptic tick and shares no interpreter lock with it.
- `DelayedRobot`: readings arrive `delay` reads late (link latency).
- `BacklashCompensatedRobot`: the inverse of each cable's play added to the commanded lengths (backlash
  feed-forward, teleop.core.control.feedforward), within the robot's length and speed limits.
- `NoisyStylus`: Gaussian noise on the stylus position (seeded).
- `LoggedDevice`: keeps every call and result (for tests and debugging).
"""

from __future__ import annotations

import collections
import dataclasses
import gc
import multiprocessing as mp
import os
import pickle
import time

import numpy as np

from devices.base import ContextDevice, DeviceError, HapticSample, RobotReading
from teleop.core.control.feedforward import TAU_S, V0_M_S, BacklashFeedforward
from teleop.core.kernels.safety import all_finite
from teleop.io.stop_signals import ignore_stop_signals

# ------------------------------------------------------------------------------------------------------------
# generic wrappers
# ------------------------------------------------------------------------------------------------------------


class Wrapper(ContextDevice):
    """Delegates everything to the wrapped device; subclasses override what they change."""

    def __init__(self, device):
        self.device = device

    @property
    def spec(self):
        return self.device.spec

    @property
    def is_open(self):
        return self.device.is_open

    def open(self):
        self.device.open()

    def close(self):
        self.device.close()

    def __getattr__(self, name):
        if name == "device":
            raise AttributeError(name)
        return getattr(self.device, name)


class DelayedRobot(Wrapper):
    """Each read() returns the reading from `delay` reads earlier (the first ones repeat the oldest)."""

    def __init__(self, robot, delay: int):
        super().__init__(robot)
        if delay < 0:
            raise ValueError("delay must be >= 0")
        self.delay = int(delay)
        self.queue = collections.deque(maxlen=self.delay + 1)

    def command_lengths(self, lengths):
        self.device.command_lengths(lengths)

    def stop(self):
        self.device.stop()

    def read(self) -> RobotReading:
        self.queue.append(self.device.read())
        return self.queue[0]


class BacklashCompensatedRobot(Wrapper):
    """Commands each cable up to half its play `width` [m] ahead of the wanted length on the side of the wanted
    motion (teleop.core.control.feedforward.BacklashFeedforward): the loop commands the lengths it wants at the cable,
    the robot gets the motor-side lengths that make a play of `width` deliver them. Each command moves at
    most v_max * `period` [s] (the robot spec's v_max; `period` the time between commands) and stays inside
    [l_min, l_max]. Readings report the wanted lengths as their commanded lengths (the loop's own commands:
    wrapper and robot together are a robot without play, so re-engaging from a reading finds a pose); the
    motor-side lengths show in their position steps. The feed-forward starts afresh at open() and after stop().
    `clock()` [s] (default time.perf_counter; a simulation passes its own) times the commands for the wanted
    rate: a loop running late sends them unevenly."""

    def __init__(self, robot, width, period: float, clock=None):
        super().__init__(robot)
        if not period > 0:
            raise ValueError("period must be > 0")
        self.width, self.period = width, float(period)
        self.clock = clock if clock is not None else time.perf_counter
        self._t = None  # clock of the previous command [s]
        self.ff = None
        self.wanted = None  # the last wanted lengths (6,) [m]
        self._src = self._out = None  # the last reading read and the one returned for it

    @property
    def compensation(self) -> dict:
        """What is added to the commands (stored in the session metadata)."""
        w = np.broadcast_to(np.asarray(self.width, dtype=float), (6,))
        return {"kind": "backlash_feedforward", "width_mm": (w * 1e3).tolist(), "period_s": self.period,
                "v0_mm_s": V0_M_S * 1e3, "tau_s": TAU_S}

    def open(self):
        self.device.open()
        self.wanted = self._src = self._out = self._t = None
        s = self.device.spec
        self.ff = BacklashFeedforward(self.width, 6, self.period, float(s.v_max), float(s.l_min), float(s.l_max))

    def command_lengths(self, lengths):
        L = np.asarray(lengths, dtype=float)
        if L.shape != (6,) or not all_finite(L):  # the robot's own check names the bad input
            self.device.command_lengths(lengths)
            return
        now = self.clock()
        x = self.ff.step(L, None if self._t is None else now - self._t)
        self._t = now
        self.device.command_lengths(x)
        self.wanted = L.copy()

    def read(self) -> RobotReading:
        r = self.device.read()
        if r is None or self.wanted is None:
            return r
        if r is not self._src:  # a robot process repeats its last reading until a new one arrives
            self._src, self._out = r, dataclasses.replace(r, commanded_lengths=self.wanted.copy())
        return self._out

    def stop(self):
        self.device.stop()
        self._t = None
        if self.ff is not None:
            self.ff.reset()


class NoisyStylus(Wrapper):
    """Adds N(0, sigma^2) [m] to each position component of the stylus readings (seeded)."""

    def __init__(self, haptic, sigma: float, seed: int = 0):
        super().__init__(haptic)
        self.sigma = float(sigma)
        self.rng = np.random.default_rng(seed)

    def read(self) -> HapticSample:
        s = self.device.read()
        p = s.measured_cp + self.rng.normal(0.0, self.sigma, 3)
        return HapticSample(t=s.t, measured_cp=p, orientation=s.orientation, measured_cv=s.measured_cv,
                            buttons=s.buttons, operator_present=s.operator_present)

    def servo_cf(self, force):
        self.device.servo_cf(force)


class LoggedDevice(Wrapper):
    """Records (method, argument or result) for every read / servo_cf / command_lengths / stop."""

    def __init__(self, device):
        super().__init__(device)
        self.log: list = []

    def read(self):
        r = self.device.read()
        self.log.append(("read", r))
        return r

    def servo_cf(self, force):
        self.log.append(("servo_cf", np.array(force, dtype=float)))
        self.device.servo_cf(force)

    def command_lengths(self, lengths):
        self.log.append(("command_lengths", np.array(lengths, dtype=float)))
        self.device.command_lengths(lengths)

    def stop(self):
        self.log.append(("stop", None))
        self.device.stop()


# ------------------------------------------------------------------------------------------------------------
# robot in its own process
# ------------------------------------------------------------------------------------------------------------

_SLOT = 256  # float64 slots of a published reading
# command block (float64): [version, 6 lengths, stop flag, quit flag, child error flag]
_CMD_N = 10
_ERR = 9  # set by the child after it has sent an error on the pipe: the parent polls the pipe only then
_BASE = ("t", "seq", "status", "boot_id")  # then fsr(6), steps(6), lengths(6), wrench(6), wrench_ok, fbg_ok,
_EXTRAS = 42                               # fbg_pm (2 x 6, RobotReading.fbg_pm), extras from slot 42


def _pack(r: RobotReading, keys: list, out: np.ndarray) -> None:
    out[0], out[1], out[2], out[3] = r.t, r.seq, r.status, r.boot_id
    out[4:10] = r.fsr_counts
    out[10:16] = r.position_steps
    out[16:22] = r.commanded_lengths
    if r.wrench_truth is None:
        out[22:28] = np.nan
        out[28] = 0
    else:
        out[22:28] = r.wrench_truth
        out[28] = 1
    if r.fbg_pm is None:
        out[29] = 0
    else:
        out[29] = 1
        out[30:42] = np.asarray(r.fbg_pm, dtype=float).ravel()[:12]
    i = _EXTRAS
    for k, w in keys:
        out[i:i + w] = np.asarray(r.extras.get(k, np.nan), dtype=float).ravel()[:w]
        i += w


def _unpack(v: np.ndarray, keys: list) -> RobotReading:
    extras, i = {}, _EXTRAS
    for k, w in keys:
        extras[k] = v[i:i + w].copy() if w > 1 else float(v[i])
        i += w
    return RobotReading(t=float(v[0]), seq=int(v[1]), fsr_counts=v[4:10].copy(), position_steps=v[10:16].copy(),
                        commanded_lengths=v[16:22].copy(), status=int(v[2]), boot_id=int(v[3]),
                        wrench_truth=v[22:28].copy() if v[28] else None, extras=extras,
                        fbg_pm=v[30:42].reshape(2, 6).copy() if v[29] else None)


def _worker(build, rate_hz: float, shm_read, shm_cmd, conn, parent_pid: int, rt_priority: int | None = None) -> None:
    """Child: build the robot (`build()`), own it, apply the latest command, read, publish, at rate_hz (sleeping,
    not spinning)."""
    ignore_stop_signals()  # the group's SIGINT/SIGTERM/SIGHUP: the loop process stops the robot in order
    try:
        if rt_priority:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(rt_priority)))
        else:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))  # do not inherit the loop's policy
            os.nice(-10)  # ahead of ordinary processes where the OS lets us, behind the real-time loop
    except (AttributeError, OSError):
        pass

    pub = np.frombuffer(shm_read, dtype=np.float64)  # [version, slot...]
    cmd = np.frombuffer(shm_cmd, dtype=np.float64)
    try:
        dev = build()
        dev.open()
        first = dev.read()
        keys = []
        for k, v in sorted((first.extras or {}).items()):
            try:
                a = np.asarray(v, dtype=float).ravel()
            except (TypeError, ValueError):
                continue
            if 0 < a.size and _EXTRAS + sum(w for _, w in keys) + a.size <= _SLOT:
                keys.append((k, int(a.size)))
        conn.send_bytes(pickle.dumps(("ok", dev.spec, keys, getattr(dev, "firmware_version", None))))
    except Exception as exc:  # noqa: BLE001 - reported to the parent as one line
        conn.send_bytes(pickle.dumps(("error", f"{type(exc).__name__}: {exc}", None, None)))
        return
    gc.collect()
    gc.freeze()  # long-lived objects out of the collector's way
    gc.disable()  # a full collection would stall the link for many milliseconds
    period = 1.0 / rate_hz
    slot = np.zeros(_SLOT)
    n_iter = 0
    last_cmd_version = 0.0
    stopped = False
    next_t = time.monotonic()
    reading = first
    try:
        while cmd[8] == 0 and os.getppid() == parent_pid:
            if cmd[7] and not stopped:
                dev.stop()
                stopped = True
            v = cmd[0]
            if v != last_cmd_version and not stopped:
                last_cmd_version = v
                dev.command_lengths(cmd[1:7].copy())
            reading = dev.read()
            _pack(reading, keys, slot)
            pub[0] += 1  # odd: being written (seqlock)
            pub[1:] = slot
            pub[0] += 1  # even: consistent
            n_iter += 1
            if n_iter % 1000 == 0:
                gc.collect(0)  # young generation only: short
            next_t += period
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                next_t = time.monotonic()
    except Exception as exc:  # noqa: BLE001 - the parent sees the error and faults
        try:
            conn.send_bytes(pickle.dumps(("error", f"{type(exc).__name__}: {exc}", None, None)))
        except OSError:
            pass
        cmd[_ERR] = 1
    finally:
        try:
            dev.stop()
        finally:
            dev.close()


class ProcessRobot(ContextDevice):
    """A Robot run in a child process at `rate_hz`; read() returns the latest published reading (same
    seq when nothing new arrived, so the loop's staleness watchdog works), command_lengths() posts the
    latest command. Errors in the child come back as DeviceError on the next read().

    Args:
        build: () -> Robot, called in the child (forked: it need not pickle) to build the robot it runs.
        name: the robot's name in error messages (its URL).
        before_fork: () -> None, run in the parent at open() before the fork (e.g. the loop's kernel warm-up:
            the child inherits what it loaded).
    """

    def __init__(self, build, name: str = "robot", rate_hz: float = 1000.0, start_timeout: float = 30.0,
                 rt_priority: int | None = None, before_fork=None):
        self.build, self.name, self.rate_hz, self.start_timeout = build, name, float(rate_hz), start_timeout
        self.rt_priority = rt_priority
        self.before_fork = before_fork
        self.is_open = False
        self.spec = None
        self.firmware_version = None

    def open(self) -> None:
        if self.before_fork is not None:
            self.before_fork()
        ctx = mp.get_context("fork")
        self.shm_read = ctx.RawArray("d", 1 + _SLOT)
        self.shm_cmd = ctx.RawArray("d", _CMD_N)
        self.pub = np.frombuffer(self.shm_read, dtype=np.float64)
        self.cmd = np.frombuffer(self.shm_cmd, dtype=np.float64)
        rx, tx = ctx.Pipe(duplex=False)
        self.proc = ctx.Process(target=_worker, name="teleop-robot", daemon=True,
                                args=(self.build, self.rate_hz, self.shm_read, self.shm_cmd, tx, os.getpid(),
                                      self.rt_priority))
        self.proc.start()
        self.rx = rx
        if not rx.poll(self.start_timeout):
            self._kill()
            raise DeviceError(f"{self.name}: robot process did not start within {self.start_timeout:g} s")
        status, spec, keys, fw = pickle.loads(rx.recv_bytes())
        if status != "ok":
            self._kill()
            raise DeviceError(f"{self.name}: {spec}")
        self.spec, self.keys, self.firmware_version = spec, keys, fw
        self.buf = np.zeros(1 + _SLOT)
        self.n_reads = 0
        self.last = None
        self.last_version = -1.0
        deadline = time.monotonic() + self.start_timeout
        while self.pub[0] < 2 and time.monotonic() < deadline:   # the first reading written whole (seqlock: 2)
            time.sleep(0.001)
        self.is_open = True

    def _kill(self) -> None:
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join()

    def close(self) -> None:
        if not self.is_open:
            return
        self.cmd[8] = 1
        self.proc.join(5.0)
        if self.proc.is_alive():
            self._kill()
        self.is_open = False

    def command_lengths(self, lengths) -> None:
        L = np.asarray(lengths, dtype=float)
        if L.shape != (6,) or not all_finite(L):
            raise DeviceError(f"{self.name}: lengths must be 6 finite numbers")
        self.cmd[1:7] = L
        self.cmd[0] += 1

    def stop(self) -> None:
        if self.is_open:
            self.cmd[7] = 1

    def read(self) -> RobotReading:
        if not self.is_open:
            raise DeviceError(f"{self.name}: read() before open()")
        self.n_reads += 1
        # the pipe (a syscall) only after the child flagged an error, and every 64th read (a killed child: EOF)
        if (self.cmd[_ERR] or not self.n_reads & 63) and self.rx.poll():
            status, msg, _, _ = pickle.loads(self.rx.recv_bytes())
            raise DeviceError(f"{self.name} (robot process): {msg}")
        for _ in range(100):  # seqlock: retry while the writer is mid-update
            v1 = self.pub[0]
            if self.last is not None and v1 == self.last_version:
                return self.last
            self.buf[:] = self.pub
            if v1 == self.buf[0] == self.pub[0] and int(v1) % 2 == 0 and v1 > 0:
                self.last = _unpack(self.buf[1:], self.keys)
                self.last_version = v1
                break
        if self.last is None:
            raise DeviceError(f"{self.name}: no reading published yet")
        return self.last
