"""The CDPR robot behind the Arduino Mega2560 link: devices.base.Robot over transport/framing/messages.

``serial:///dev/ttyACM0?baud=1000000`` -> ArduinoRobot. ``open()`` only handshakes (HELLO: boot id,
firmware version); nothing moves before ``home(lengths)``. ``command_lengths`` converts metres to motor
steps and sends without waiting; ``read()`` returns the newest telemetry (``t`` is the host receive time,
``time.monotonic()`` [s]) and solicits the next one, so one host frame and one telemetry frame cross per
tick. A new boot id (firmware reset) is detected on the next frame and motion is refused until re-homed;
telemetry gaps, duplicates and reordering are counted by sequence number; ``stop()`` latches until
``enable()`` or ``home()``.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

import numpy as np

from devices.arduino import messages as msg
from devices.arduino.framing import encode_frame
from devices.arduino.transport import SerialTransport
from devices.base import ContextDevice, DeviceError, RobotReading, RobotSpec
from teleop.core.errors import InputError

DEFAULT_BAUD = 1_000_000


@dataclass
class LinkStats:
    """Host-side link counters.

    Attributes:
        frames: telemetry-side frames accepted.
        errors: error kind (framing kinds, "malformed") -> count of rejected inputs.
        gaps: firmware frames missing (sum of sequence gaps).
        duplicates, reordered: firmware frames dropped as repeated or older than the last one.
        resets: firmware resets seen (boot id changes).
        timeouts: requests whose reply did not arrive within the timeout (then resent).
    """

    frames: int = 0
    errors: dict = field(default_factory=dict)
    gaps: int = 0
    duplicates: int = 0
    reordered: int = 0
    resets: int = 0
    timeouts: int = 0


class ArduinoRobot(ContextDevice):
    """Robot protocol over the framed serial link to the Mega2560 firmware.

    Args:
        port: serial device path or pyserial URL.
        baud: line rate [bit/s].
        spec: limits (steps_per_m converts lengths to steps).
        timeout_s: reply timeout for the blocking calls (handshake, home, stop, diag) [s].
        boot_timeout_s: how long open() retries the handshake (a real Mega reboots on open) [s].
        home_lengths: (6,) cable lengths [m] the rig is set up at; when given, open() declares them
            (HOME) after the handshake. A firmware reset later still needs an explicit home().
    """

    def __init__(self, port: str, baud: int = DEFAULT_BAUD, spec: RobotSpec = RobotSpec(),
                 timeout_s: float = 0.25, boot_timeout_s: float = 3.0, home_lengths=None):
        if baud <= 0 or timeout_s <= 0 or boot_timeout_s <= 0:
            raise InputError(f"serial robot '{port}': baud, timeout and boot timeout must be positive")
        travel = (spec.l_max - spec.l_min) * spec.steps_per_m
        if travel > msg.STEP_LIMIT:  # every commanded length, from any home in range, within the firmware's steps
            raise InputError(f"serial robot '{port}': cable lengths {spec.l_min * 1e3:g} to {spec.l_max * 1e3:g} mm "
                             f"span {travel:.0f} motor steps; the firmware holds +-{msg.STEP_LIMIT} "
                             f"({msg.STEP_LIMIT / spec.steps_per_m * 1e3:.0f} mm): narrow l_min_mm..l_max_mm")
        self.port, self.baud, self.spec = port, int(baud), spec
        self.home_lengths = None
        if home_lengths is not None:
            try:
                self.home_lengths = self._check_lengths(home_lengths)
            except ValueError as exc:
                raise InputError(f"serial robot '{port}': home lengths: {exc}") from None
        self.timeout_s, self.boot_timeout_s = float(timeout_s), float(boot_timeout_s)
        self.is_open = False
        self.stats = LinkStats()
        self.hello: msg.HelloReply | None = None
        self._transport: SerialTransport | None = None
        self._cond = threading.Condition()
        self._reset_state()

    def _reset_state(self) -> None:
        self._tx_seq = 0
        self._rx_seq: int | None = None
        self._rx_count = 0  # telemetry-side frames counted by sequence number (unwrapped, monotonic)
        self._boot_id: int | None = None
        self._latest: msg.Telemetry | None = None
        self._latest_t = 0.0
        self._latest_count = 0
        self._replies: list[tuple[msg.Telemetry, float]] = []
        self._diag: msg.DiagReply | None = None
        self._hello_count = 0
        self._sent_since_read = False
        self._homed = False
        self._stopped = False
        self._reset_seen = False
        self._home_lengths = np.zeros(self.spec.n_cables)
        self._pending: dict[int, np.ndarray] = {}
        self._commanded = np.full(self.spec.n_cables, np.nan)

    # ----------------------------------------------------------------- lifecycle
    def open(self) -> None:
        self._reset_state()
        self.stats = LinkStats()
        self._transport = SerialTransport(self.port, self.baud, self._on_frames)
        self._transport.open()
        try:
            deadline = time.monotonic() + self.boot_timeout_s
            while True:
                seen = self._hello_count
                self._send(msg.Hello(self._next_seq()))
                if self._wait(lambda: self._hello_count > seen, self.timeout_s):
                    break
                if time.monotonic() > deadline:
                    raise DeviceError(f"serial robot '{self.port}': no HELLO reply within "
                                      f"{self.boot_timeout_s} s (firmware not running?)")
            if self.hello.protocol != msg.PROTOCOL_VERSION:
                raise DeviceError(f"serial robot '{self.port}': firmware speaks protocol {self.hello.protocol}, "
                                  f"host speaks {msg.PROTOCOL_VERSION}")
            check_speed_limit(self.spec, self.hello, self.port)
        except Exception:
            self._transport.close()
            self._transport = None
            raise
        with self._cond:
            self.stats = LinkStats()  # bytes before the handshake (a half frame at power-up) don't count
            self._reset_seen = False
        self.is_open = True
        if self.home_lengths is not None:
            try:
                self.home(self.home_lengths)
            except Exception:
                self.close()
                raise

    def close(self) -> None:
        if self._transport is not None:
            try:
                self._send(msg.Stop(self._next_seq()))  # best effort; the firmware watchdog backs it up
                time.sleep(0.002)
            except DeviceError:
                pass
            self._transport.close()
            self._transport = None
        self.is_open = False

    # ----------------------------------------------------------------- Robot protocol
    def home(self, lengths) -> msg.Telemetry:
        """Declare the current cable lengths (6,) [m] as home (motor steps 0); enables motion."""
        home = self._check_lengths(lengths)
        reply = self._request(lambda seq: msg.Home(seq, (0,) * self.spec.n_cables))
        if reply.status & msg.Status.REJECTED or not reply.status & msg.Status.HOMED:
            raise DeviceError(f"serial robot '{self.port}': HOME refused (status {reply.status:#04x})")
        with self._cond:
            self._home_lengths, self._homed, self._stopped, self._reset_seen = home, True, False, False
            self._commanded = home.copy()
        return reply

    def enable(self) -> msg.Telemetry:
        """Clear a STOP or watchdog latch (the motors hold where they are)."""
        reply = self._request(msg.Enable)
        if reply.status & msg.Status.REJECTED:
            raise DeviceError(f"serial robot '{self.port}': ENABLE refused (status {reply.status:#04x})")
        self._stopped = False
        return reply

    def command_lengths(self, lengths) -> None:
        """Command cable lengths (6,) [m]; sent at once, applied by the firmware rate-limited."""
        self._require_open()
        if self._reset_seen:
            raise DeviceError(f"serial robot '{self.port}': firmware reset detected (new boot id); "
                              "home() before any motion")
        if not self._homed:
            raise DeviceError(f"serial robot '{self.port}': not homed; call home(lengths) first")
        if self._stopped:
            raise DeviceError(f"serial robot '{self.port}': stopped; call enable() to move again")
        target = self._check_lengths(lengths)
        steps = msg.lengths2steps(target, self._home_lengths, self.spec.steps_per_m)
        seq = self._next_seq()
        with self._cond:
            self._pending = {k: v for k, v in self._pending.items() if msg.seq_diff(seq, k) < 64}
            self._pending[seq] = target
        self._send(msg.Command(seq, tuple(int(s) for s in steps)))

    def read(self) -> RobotReading:
        """Newest telemetry as a RobotReading; solicits the next one (HEARTBEAT) if nothing was sent."""
        self._require_open()
        if self._latest is None:
            self._request(msg.Heartbeat)
        elif not self._sent_since_read:
            self._send(msg.Heartbeat(self._next_seq()))
        self._sent_since_read = False
        with self._cond:
            return self._reading(self._latest, self._latest_t, self._latest_count)

    def read_fresh(self) -> RobotReading:
        """Send a HEARTBEAT and wait for its telemetry (one round trip)."""
        self._require_open()
        reply = self._request(msg.Heartbeat)
        with self._cond:
            return self._reading(reply, self._latest_t, self._latest_count)

    def heartbeat(self) -> None:
        """Keep the firmware watchdog fed without commanding motion."""
        self._send(msg.Heartbeat(self._next_seq()))

    def stop(self) -> None:
        """Stop all motors now and latch (firmware obeys STOP whatever its sequence number)."""
        self._require_open()
        for _ in range(3):
            seq = self._send(msg.Stop(self._next_seq()))
            try:
                reply = self._wait_reply(seq)
            except DeviceError:
                continue
            if reply.status & msg.Status.STOPPED:
                self._stopped = True
                return
        raise DeviceError(f"serial robot '{self.port}': STOP not confirmed (the firmware watchdog stops "
                          f"the motors {self.hello.watchdog_ms if self.hello else '?'} ms after silence)")

    def diag(self) -> msg.DiagReply:
        """Firmware clock and error counters."""
        self._require_open()
        for _ in range(3):
            with self._cond:
                before = self._diag
            self._send(msg.DiagRequest(self._next_seq()))
            if self._wait(lambda: self._diag is not before, self.timeout_s):
                return self._diag
            self.stats.timeouts += 1
        raise DeviceError(f"serial robot '{self.port}': no DIAG reply in 3 attempts of {self.timeout_s} s")

    @property
    def boot_id(self) -> int | None:
        return self._boot_id

    @property
    def is_homed(self) -> bool:
        return self._homed and not self._reset_seen

    @property
    def reset_detected(self) -> bool:
        return self._reset_seen

    # ----------------------------------------------------------------- internals
    def _require_open(self) -> None:
        if self._transport is None:
            raise DeviceError(f"serial robot '{self.port}' is not open")

    def _check_lengths(self, lengths) -> np.ndarray:
        x = np.asarray(lengths, dtype=float)
        if x.shape != (self.spec.n_cables,) or not np.all(np.isfinite(x)):
            raise ValueError(f"expected {self.spec.n_cables} finite cable lengths [m], got {lengths!r}")
        if np.any(x < self.spec.l_min) or np.any(x > self.spec.l_max):
            raise ValueError(f"cable lengths {x} outside [{self.spec.l_min}, {self.spec.l_max}] m")
        return x

    def _next_seq(self) -> int:
        self._tx_seq = (self._tx_seq + 1) % msg.SEQ_MOD
        return self._tx_seq

    def _send(self, message) -> int:
        self._require_open()
        self._transport.write(encode_frame(msg.encode(message)))
        self._sent_since_read = True
        return message.seq

    def _wait(self, predicate, timeout: float) -> bool:
        with self._cond:
            return self._cond.wait_for(predicate, timeout)

    def _request(self, make, attempts: int = 3) -> msg.Telemetry:
        """Send make(seq) with a fresh seq and wait for its TELEMETRY; resend (new seq) when the reply is
        lost (a frame dropped on an overloaded link). Raises DeviceError after `attempts`."""
        for attempt in range(attempts):
            seq = self._send(make(self._next_seq()))
            try:
                return self._wait_reply(seq)
            except DeviceError:
                self.stats.timeouts += 1
                if attempt == attempts - 1:
                    raise
        raise AssertionError("unreachable")

    def _wait_reply(self, seq: int) -> msg.Telemetry:
        tag = seq & 0xFF
        found: list = []

        def arrived() -> bool:
            found[:] = [r for r, _ in self._replies if r.reply_to == tag]
            return bool(found)

        if not self._wait(arrived, self.timeout_s):
            raise DeviceError(f"serial robot '{self.port}': no reply to frame {seq} within {self.timeout_s} s")
        return found[-1]

    def _reading(self, t: msg.Telemetry, t_rx: float, count: int) -> RobotReading:
        return RobotReading(
            t=t_rx, seq=count, fsr_counts=np.array(t.adc_counts, dtype=int),
            position_steps=np.array(t.position_steps, dtype=int), commanded_lengths=self._commanded.copy(),
            status=t.status, boot_id=self._boot_id or 0,
            extras={"link_seq": t.seq, "reply_to": t.reply_to, "rejected": bool(t.status & msg.Status.REJECTED),
                    "lengths": msg.steps2lengths(t.position_steps, self._home_lengths, self.spec.steps_per_m)})

    def _firmware_reset(self) -> None:
        self._reset_seen, self._homed = True, False
        self.stats.resets += 1

    def _on_frames(self, payloads: list, errors: list, t_rx: float) -> None:
        """Reader thread: account errors, track sequence numbers and boot id, store replies."""
        with self._cond:
            for kind in errors:
                self.stats.errors[kind] = self.stats.errors.get(kind, 0) + 1
            for payload in payloads:
                try:
                    m = msg.decode(payload)
                except msg.MessageError:
                    self.stats.errors["malformed"] = self.stats.errors.get("malformed", 0) + 1
                    continue
                if isinstance(m, msg.HelloReply):
                    if self._boot_id is not None and m.boot_id != self._boot_id:
                        self._firmware_reset()
                        self._rx_seq = None
                    self._boot_id, self.hello = m.boot_id, m
                    self._hello_count += 1
                elif isinstance(m, msg.Telemetry) and self._boot_id is not None \
                        and m.boot_tag != self._boot_id & 0xF:
                    self._firmware_reset()
                    self._rx_seq = None
                kind, missing = msg.classify_seq(self._rx_seq, m.seq)
                if kind == "duplicate":
                    self.stats.duplicates += 1
                    continue
                if kind == "old":
                    self.stats.reordered += 1
                    continue
                self.stats.gaps += missing
                self._rx_count += 1 + missing
                self._rx_seq = m.seq
                self.stats.frames += 1
                if isinstance(m, msg.Telemetry):
                    self._latest, self._latest_t, self._latest_count = m, t_rx, self._rx_count
                    self._replies = self._replies[-31:] + [(m, t_rx)]
                    applied = [s for s in self._pending if s & 0xFF == m.reply_to]
                    for s in applied:
                        target = self._pending.pop(s)
                        if not m.status & msg.Status.REJECTED:
                            self._commanded = target
                elif isinstance(m, msg.DiagReply):
                    self._diag = m
            self._cond.notify_all()


def spec_for(geometry) -> RobotSpec:
    """The robot's limits for a geometry (teleop.core.geometry.Geometry): its cable length range l_min..l_max
    [m] and cable speed v_max [m/s], the motors' steps per metre unchanged (devices.base.RobotSpec)."""
    return RobotSpec(l_min=float(geometry.l_min), l_max=float(geometry.l_max), v_max=float(geometry.v_max))


def check_speed_limit(spec: RobotSpec, hello: msg.HelloReply, port: str) -> None:
    """InputError when the host's cable speed `spec.v_max` [m/s] is faster than the firmware moves a motor
    (HELLO_REPLY's v_max [steps/s], V_MAX_STEPS of firmware/protocol.h, one step/s of rounding allowed): the
    commands would outrun the motors and the realized lengths lag the commanded ones."""
    asked = spec.v_max * spec.steps_per_m
    if asked > hello.v_max_steps_per_s + 1:
        raise InputError(f"serial robot '{port}': geometry v_max_mm_s {spec.v_max * 1e3:g} is faster than the "
                         f"firmware's {hello.v_max_steps_per_s / spec.steps_per_m * 1e3:.3g} mm/s "
                         f"({hello.v_max_steps_per_s} steps/s, V_MAX_STEPS in firmware/protocol.h): lower "
                         "v_max_mm_s or rebuild the firmware")


def from_url(parsed, options: dict) -> ArduinoRobot:
    """``serial:///dev/ttyACM0?baud=1000000&timeout=0.25&home_mm=30,30,30,30,30,30`` -> ArduinoRobot
    (not opened; with home_mm, open() declares those cable lengths as home). The option `geometry`, a
    teleop.core.geometry.Geometry given by the wiring (teleop.loop.devices_by_url, `--geometry`), not by the
    URL, sets the length and speed limits (`spec_for`; the default: RobotSpec's, the seed robot's)."""
    geometry = options.get("geometry")
    if isinstance(geometry, str):
        raise InputError("serial URL: geometry is not a URL option; give the geometry file with --geometry")
    allowed = {"baud", "timeout", "home_mm", "geometry"}
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise InputError(f"serial URL: unknown option(s) {', '.join(unknown)} (expected: baud, timeout, home_mm)")
    port = parsed.path or parsed.netloc
    if not port:
        raise InputError("serial URL: expected serial:///dev/ttyXXX (a device path)")
    try:
        baud = int(options.get("baud", DEFAULT_BAUD))
        timeout = float(options.get("timeout", 0.25))
    except (TypeError, ValueError):
        raise InputError(f"serial URL: baud must be an integer and timeout a number, got "
                         f"baud={options.get('baud')!r} timeout={options.get('timeout')!r}") from None
    home = None
    if "home_mm" in options:
        try:
            home = np.array([float(v) for v in str(options["home_mm"]).split(",")]) * 1e-3
        except ValueError:
            raise InputError(f"serial URL: home_mm must be comma-separated numbers [mm], "
                             f"got {options['home_mm']!r}") from None
    spec = RobotSpec() if geometry is None else spec_for(geometry)
    return ArduinoRobot(port, baud=baud, spec=spec, timeout_s=timeout, home_lengths=home)
