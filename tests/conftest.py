"""Test-wide settings: hypothesis runs derandomised (same examples every run) with no deadline; and how the
suite shares out over pytest-xdist's workers (pyproject.toml addopts: `-n 2 --dist loadgroup`).

Every test is free to run on either worker, except:
- REALTIME: tests that pace on the wall clock or time out on it (the live view at 100 Hz, Foxglove Studio in
  Chromium, paced sessions asserting their state, stop signals and SIGKILLed sessions, the simavr firmware
  over a pty with its watchdog, the robot process, real Dask clusters) run one after the other on one
  worker, never two at once; the other worker meanwhile runs the rest.
- tests that share a module- or session-scoped fixture of the suite's own (a recorded session, a built
  firmware) stay together on one worker, so that the fixture is made once, not once per worker.
`-n 0` runs the suite in one process (the groups are then ignored)."""

import os

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
    "tests/devices/arduino/",
    "tests/devices/test_process_robot_warm.py",
    "tests/apps/campaign/test_dask_campaign.py",
    "tests/apps/campaign/test_diagnose_scheduler.py",
    "tests/apps/test_feedforward_end_to_end.py",    # a paced 8 s session that must end ENABLED
)


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


def pytest_configure(config):
    config.addinivalue_line("markers", "xdist_group(name): run on the one worker that runs the group `name`")


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups into the node ids
def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("xdist_group"):
            continue
        path = item.nodeid.split("::")[0]
        group = REALTIME_GROUP if path.startswith(REALTIME) else _shared_fixture_scope(item)
        if group:
            item.add_marker(pytest.mark.xdist_group(group))
