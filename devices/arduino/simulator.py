"""Run the real firmware in simavr (the cdpr_sim harness) behind a pseudo-terminal.

    with EmulatedMega(harness_exe, firmware_elf) as mega:
        robot = ArduinoRobot(mega.port)        # pyserial on /dev/pts/N at 1 Mbaud
        mega.status()["last_step_ns"]          # observations in emulated time

The harness paces emulation to the wall clock, counts step pulses into cable positions, feeds the ADC
from a tension model, and answers `status` / `reset` on a control pipe.
"""

from __future__ import annotations

import subprocess
import threading
from pathlib import Path

from devices.base import DeviceError

_INT_LISTS = {"pos", "adc_mv"}


def parse_status(line: str) -> dict:
    """'status k=v k=a,b ...' -> {k: int or list[int]}."""
    words = line.split()
    if not words or words[0] != "status":
        raise DeviceError(f"cdpr_sim: unexpected control reply {line!r}")
    out: dict = {}
    for word in words[1:]:
        key, _, value = word.partition("=")
        out[key] = [int(v) for v in value.split(",")] if key in _INT_LISTS else int(value)
    return out


class EmulatedMega:
    """The harness process: `port` is the pty path once open."""

    def __init__(self, harness: Path, firmware: Path, startup_timeout_s: float = 10.0):
        self.harness, self.firmware = Path(harness), Path(firmware)
        self.startup_timeout_s = startup_timeout_s
        self.port: str | None = None
        self._proc: subprocess.Popen | None = None
        self._lock = threading.Lock()

    def open(self) -> None:
        self._proc = subprocess.Popen([str(self.harness), str(self.firmware)], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, bufsize=1)
        line = self._readline(self.startup_timeout_s)
        if not line.startswith("pty "):
            self.close()
            raise DeviceError(f"cdpr_sim did not start: {line!r}")
        self.port = line.split()[1]

    def _readline(self, timeout: float) -> str:
        result: list[str] = []
        reader = threading.Thread(target=lambda: result.append(self._proc.stdout.readline()), daemon=True)
        reader.start()
        reader.join(timeout)
        if not result or not result[0]:
            raise DeviceError("cdpr_sim: no reply on the control pipe (harness died?)")
        return result[0].strip()

    def request(self, line: str, timeout: float = 5.0) -> str:
        with self._lock:
            if self._proc is None or self._proc.poll() is not None:
                raise DeviceError("cdpr_sim is not running")
            self._proc.stdin.write(line + "\n")
            self._proc.stdin.flush()
            return self._readline(timeout)

    def status(self) -> dict:
        """Emulated time [ns], last UART byte in [ns], last step pulse [ns], positions, ADC inputs [mV], ..."""
        return parse_status(self.request("status"))

    def turnaround_s(self) -> list[float]:
        """Firmware turnaround of recent requests on the emulated clock [s]: a request's delimiter into the
        UART -> the reply's delimiter out (reply line time included; the last 4096)."""
        reply = self.request("turnaround")
        words = reply.split()
        if not words or words[0] != "turnaround":
            raise DeviceError(f"cdpr_sim: unexpected control reply {reply!r}")
        return [int(v) * 1e-9 for v in words[1].split(",")] if len(words) > 1 else []

    def reset(self) -> None:
        """Reset the MCU (firmware restarts with a new boot id; cable positions persist)."""
        reply = self.request("reset")
        if reply != "ok reset":
            raise DeviceError(f"cdpr_sim: reset failed: {reply!r}")

    def close(self) -> None:
        if self._proc is None:
            return
        try:
            if self._proc.poll() is None:
                self._proc.stdin.write("quit\n")
                self._proc.stdin.flush()
            self._proc.wait(timeout=2.0)
        except (OSError, subprocess.TimeoutExpired):
            self._proc.kill()
            self._proc.wait()
        self._proc = None

    def __enter__(self):
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()
