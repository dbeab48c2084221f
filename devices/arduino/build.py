"""Build the firmware (.elf) and the simavr harness out of the source tree; used by the tests and by hand.

    python -m devices.arduino.build [BUILD_DIR]   # default ~/.cache/cdpr-teleop/arduino

Missing tools raise ToolchainMissing naming the Debian packages to install.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
FIRMWARE_DIR = HERE / "firmware"
HARNESS_SRC = HERE / "harness" / "cdpr_sim.c"
ARDUINO_CORE = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino")
SIMAVR_HEADER = Path("/usr/include/simavr/sim_avr.h")
PACKAGES = "gcc-avr avr-libc arduino-core-avr simavr libsimavr-dev libelf-dev pkg-config make gcc"


class ToolchainMissing(RuntimeError):
    """The AVR toolchain, Arduino core or libsimavr is not installed."""


def default_build_dir() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "cdpr-teleop" / "arduino"


def check_toolchain() -> None:
    """Raise ToolchainMissing with one line naming what is absent."""
    missing = [tool for tool in ("avr-gcc", "avr-g++", "avr-objcopy", "make", "gcc", "pkg-config")
               if shutil.which(tool) is None]
    if not ARDUINO_CORE.is_dir():
        missing.append(f"Arduino core ({ARDUINO_CORE})")
    if not SIMAVR_HEADER.is_file():
        missing.append(f"libsimavr headers ({SIMAVR_HEADER})")
    if missing:
        raise ToolchainMissing(f"missing {', '.join(missing)}; install the Debian packages: {PACKAGES} "
                               "(scripts/install-system-deps.sh)")


def _run(cmd: list[str], what: str) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{what} failed ({' '.join(cmd)}):\n{proc.stdout}\n{proc.stderr}")


def build_firmware(build_dir: Path | None = None, jobs: int = 2) -> Path:
    """make the firmware into build_dir/firmware -> path of cdpr_link.elf (incremental)."""
    check_toolchain()
    out = Path(build_dir or default_build_dir()) / "firmware"
    _run(["make", "-s", f"-j{jobs}", "-C", str(FIRMWARE_DIR), f"BUILD_DIR={out}"], "firmware build")
    return out / "cdpr_link.elf"


def build_harness(build_dir: Path | None = None) -> Path:
    """gcc the simavr harness against libsimavr -> path of the executable (rebuilt when the source changes)."""
    check_toolchain()
    out = Path(build_dir or default_build_dir())
    out.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha256(HARNESS_SRC.read_bytes()).hexdigest()[:12]
    exe = out / f"cdpr_sim-{digest}"
    if exe.exists():
        return exe
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "simavr"], capture_output=True, text=True)
    simavr = flags.stdout.split() if flags.returncode == 0 else ["-I/usr/include/simavr", "-lsimavr"]
    tmp = exe.with_suffix(".tmp")
    _run(["gcc", "-O2", "-Wall", "-o", str(tmp), str(HARNESS_SRC), *simavr, "-lelf", "-lutil"], "harness build")
    tmp.replace(exe)
    return exe


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    build_dir = Path(args[0]) if args else None
    print(build_firmware(build_dir))
    print(build_harness(build_dir))
    return 0


if __name__ == "__main__":
    sys.exit(main())
