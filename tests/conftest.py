"""Test-wide settings: hypothesis runs derandomised (same examples every run) with no deadline; and how the
suite shares out over pytest-xdist's workers (pyproject.toml addopts: `-n 3 --dist loadgroup`).

Every test is free to run on any worker, except:
- REALTIME: tests that pace on the wall clock or time out on it (the live view at 100 Hz, Foxglove Studio in
  Chromium, paced sessions asserting their state, stop signals and SIGKILLed sessions, the simavr firmware
  over a pty with its watchdog, the robot process, real Dask clusters) run one after the other on one
  worker, never two at once; the other workers meanwhile run the rest. Three workers on the two cores: the
  paced tests mostly wait, and a third worker uses the core they leave. A worker whose first test is not a
  paced one lowers its priority (nice, for the rest of its life and its child processes'), so that the paced
  tests keep a core when they want one. The paced tests are the largest group, so pytest-xdist hands them
  out first (--dist loadgroup orders the groups by size): their worker starts with one and keeps its
  priority.
- tests that share a module- or session-scoped fixture of the suite's own (a recorded session, a built
  firmware) stay together on one worker, so that the fixture is made once, not once per worker.
`-n 0` runs the suite in one process (the groups are then ignored).

A run of the whole suite (no paths given: pyproject's testpaths) first fills numba's on-disk cache in two
processes, one per core, while the workers start and collect (tests/_warm_kernels.py): on a cold cache (a
fresh clone, any kernel source changed) every worker, `teleop` child process and Dask worker would otherwise
compile the same kernels again. The tests start once both are done. A warm cache costs their start only."""

import os
import subprocess
import sys
from pathlib import Path

import matplotlib
import pytest
from hypothesis import HealthCheck, settings

matplotlib.use("Agg")

settings.register_profile("ci", derandomize=True, deadline=None, max_examples=60,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REALTIME_GROUP = "realtime"
REALTIME = (
    "tests/browser/",
    "tests/loop/live/",
    "tests/loop/test_replay.py",                    # a paced 1 s session counted in ticks
    "tests/io/test_stop_signals.py",
    "tests/io/recording/test_recording_kill.py",
    "tests/io/recording/test_recording_orphan.py",
    "tests/devices/arduino/test_arduino_firmware.py",   # simavr over a pty (framing, messages: host-side only)
    "tests/devices/arduino/test_arduino_robot.py",
    "tests/devices/arduino/test_arduino_watchdog.py",
    "tests/devices/test_process_robot_warm.py",
    "tests/apps/campaign/test_dask_campaign.py",
    "tests/apps/campaign/test_diagnose_scheduler.py",
)


NICE_BESIDE_REALTIME = 10  # the priority the other workers drop to (CFS: about 1/9 the weight of nice 0)


def _group(item) -> str | None:
    mark = item.get_closest_marker("xdist_group")
    return None if mark is None else (mark.args[0] if mark.args else mark.kwargs.get("name"))


def _shared_fixture_scope(item) -> str | None:
    """Node id of the widest module- or session-scoped fixture of the suite's own that `item` uses, if any
    (pytest's own, like tmp_path_factory, and this file's are left out: every worker has its own anyway)."""
    info = getattr(item, "_fixtureinfo", None)
    best = None
    for defs in (info.name2fixturedefs.values() if info else ()):
        fd = defs[-1]
        if fd.scope in ("module", "package", "session") and fd.baseid.startswith("tests/"):  # not this file's
            if best is None or len(fd.baseid) < len(best):  # the conftest's directory before a module
                best = fd.baseid
    return best


_warming: list = []  # the cache-filling processes of a whole-suite run, until they are done


def pytest_configure(config):
    config.addinivalue_line("markers", "xdist_group(name): run on the one worker that runs the group `name`")
    whole_suite = config.args_source == pytest.Config.ArgsSource.TESTPATHS
    if whole_suite and not hasattr(config, "workerinput"):  # the controller (or the one process of -n 0)
        root = Path(__file__).resolve().parents[1]
        _warming.extend(subprocess.Popen([sys.executable, "-m", "tests._warm_kernels", part], cwd=root,
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                        for part in ("loop", "diagnosis"))


def _warmed() -> None:
    """Wait for the cache-filling processes (their failure is the tests' to show: they compile then)."""
    while _warming:
        _warming.pop().wait()


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_node_collection_finished(node, ids):
    _warmed()  # the controller schedules no test before the cache is full


def pytest_collection_finish(session):
    _warmed()  # -n 0


_first_test = True  # this process has not run a test yet


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    global _first_test
    if _first_test and hasattr(item.config, "workerinput"):  # a pytest-xdist worker's first test
        if _group(item) != REALTIME_GROUP:
            os.nice(NICE_BESIDE_REALTIME)
    _first_test = False


def pytest_unconfigure(config):
    for proc in _warming:  # a run ended before its tests (an error, Ctrl-C): not left compiling
        proc.kill()
        proc.wait()


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups into the node ids
def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("xdist_group"):
            continue
        path = item.nodeid.split("::")[0]
        group = REALTIME_GROUP if path.startswith(REALTIME) else _shared_fixture_scope(item)
        if group:
            item.add_marker(pytest.mark.xdist_group(group))
