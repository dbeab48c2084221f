"""Serial transport: pyserial port + a reader thread that runs the stream decoder.

The reader thread hands each received batch to a callback as (payloads, error kinds, t_rx) where t_rx is
``time.monotonic()`` at receipt [s]; writes go straight to the port from the caller's thread.
"""

from __future__ import annotations

import threading
import time
from typing import Callable

from devices.arduino.framing import DecoderState, decode_stream
from devices.base import DeviceError, DeviceUnavailable

OnFrames = Callable[[list, list, float], None]


class SerialTransport:
    """A framed byte link over a serial port (pyserial URL or device path).

    Args:
        port: device path (``/dev/ttyACM0``, a pty) or any pyserial URL (``loop://``).
        baud: line rate [bit/s].
        on_frames: callback(payloads, errors, t_rx) from the reader thread.
    """

    def __init__(self, port: str, baud: int, on_frames: OnFrames):
        self.port, self.baud, self._on_frames = port, int(baud), on_frames
        self._serial = None
        self._thread: threading.Thread | None = None
        self._running = False
        self._write_lock = threading.Lock()
        self.bytes_in = 0
        self.bytes_out = 0

    @property
    def is_open(self) -> bool:
        return self._serial is not None

    def open(self) -> None:
        import serial  # heavy import kept off module import

        try:
            self._serial = serial.serial_for_url(self.port, baudrate=self.baud, timeout=0.02,
                                                 write_timeout=0.5)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DeviceUnavailable(f"serial port '{self.port}': cannot open ({exc})") from None
        self._serial.reset_input_buffer()
        self._running = True
        self._thread = threading.Thread(target=self._read_loop, name=f"serial-reader {self.port}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._running = False
        if self._thread is not None:
            self._thread.join(timeout=1.0)
            self._thread = None
        if self._serial is not None:
            self._serial.close()
            self._serial = None

    def write(self, data: bytes) -> None:
        """Send bytes now; raises DeviceError when the port fails."""
        if self._serial is None:
            raise DeviceError(f"serial port '{self.port}' is not open")
        try:
            with self._write_lock:
                self._serial.write(data)
        except Exception as exc:  # pyserial raises SerialException, OSError or SerialTimeoutException
            raise DeviceError(f"serial port '{self.port}': write failed ({exc})") from None
        self.bytes_out += len(data)

    def _read_loop(self) -> None:
        state = DecoderState()
        ser = self._serial
        while self._running:
            try:
                data = ser.read(max(1, ser.in_waiting))
            except Exception:  # port gone: the host watchdog sees the silence
                time.sleep(0.01)
                continue
            if not data:
                continue
            t_rx = time.monotonic()
            self.bytes_in += len(data)
            state, payloads, errors = decode_stream(state, data)
            if payloads or errors:
                self._on_frames(payloads, errors, t_rx)
