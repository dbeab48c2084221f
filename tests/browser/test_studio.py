"""The operator's view in the real Foxglove Studio 1.48 (npm @foxglove/studio-base, its webpack build), in headless
Debian Chromium through puppeteer-core (tests/browser/studio.mjs), connected to `teleop session --live` with the
shipped examples/foxglove-layout.json, then opening that session's recording.

Asserted as a person would see it: no problems listed, every panel of the layout receiving, a fault line in the
log panel after an induced fault (the robot process paused until the loop's staleness limit trips), the end
effector drawn in the 3D panel (pixels of its colour inside the panel); the recording opens with no problems,
every topic listed with the count the project's own reader gives. Last, the same page opens
examples/foxglove-layout-fbg.json on a second session, with the FBG sensors (`sim://robot?sensor=fbg`): every
panel of that layout receiving, its FBG panel too (the default layout has no FBG panel: in an FSR session it
would stay empty). The screenshots stay in the test's tmp dir (live-1.png, live.png, fault.png, recording.png,
recording-problems.png, live-fbg-1.png, live-fbg.png) for a person to look at.

The session is the simulated stylus and robot, paced in real time (--no-realtime: time-sharing beside Chromium)
with the robot in its own process, which is what lets a fault be induced from outside; the simulated clock
(--sim-clock) needs the robot inline and runs as fast as it can, which is not a live view. The staleness limit
is raised to 500 ms so that a starved loop does not fault by itself; the test stops the session with SIGTERM.

Needs node and Debian's chromium (scripts/install-system-deps.sh installs both and runs `npm ci --prefix
tests/browser`); skipped only when either is missing.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
from collections import Counter
from pathlib import Path

import pytest

from teleop.io.recording import read_session
from tests.loop.live._client import served_port, spawn_session, start_session
from teleop.loop.live.channels import EE_COLOR, EE_FAULT_COLOR

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
LAYOUT = ROOT / "examples" / "foxglove-layout.json"
LAYOUT_FBG = ROOT / "examples" / "foxglove-layout-fbg.json"
NODE = shutil.which("node")
CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None)
STALE_MS = 500.0  # the session's staleness limit: far above the jitter of a loop sharing 2 cores with Chromium
FAULT_WAIT_S = 20.0  # the robot process is paused until Studio shows the fault, at most this long
SESSION_S = 600.0  # longer than the test: it stops the session (SIGTERM) once Studio has shown the fault

pytestmark = pytest.mark.skipif(NODE is None or CHROMIUM is None,
                                reason=f"needs node ({NODE or 'missing'}) and Debian's chromium "
                                       f"({CHROMIUM or 'missing'}): scripts/install-system-deps.sh")


def rgb(color) -> list:
    return [round(255 * c) for c in color[:3]]


def children(pid: int) -> list:
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        out += [int(c) for c in (task / "children").read_text().split()]
    return out


def listening_inodes(port: int) -> set:
    inodes = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            f = line.split()
            if int(f[1].rsplit(":", 1)[1], 16) == port and f[3] == "0A":  # LISTEN
                inodes.add(f[9])
    return inodes


def robot_process(session_pid: int, port: int, recording: Path) -> int:
    """The session's robot process: the child that neither serves the live view (its listening socket) nor
    writes the recording (its open file)."""
    sockets = {f"socket:[{i}]" for i in listening_inodes(port)}
    found = []
    for c in children(session_pid):
        try:
            fds = {os.readlink(p) for p in Path(f"/proc/{c}/fd").iterdir()}
        except (FileNotFoundError, ProcessLookupError):
            continue
        if not fds & sockets and str(recording) not in fds:
            found.append(c)
    assert len(found) == 1, f"expected one robot process among {children(session_pid)}, found {found}"
    return found[0]


def shown_count(topic: str, text: str) -> int | None:
    """The message count Studio's topic list shows for `topic` (lines: topic, schema, count, rate)."""
    m = re.search(rf"^{re.escape(topic)}\n[^\n]*\n([\d,]+)\n", text, re.M)
    return None if m is None else int(m.group(1).replace(",", ""))


def check_every_panel_receiving(layout: dict, live: dict, shots: str) -> None:
    """Every panel of `layout` receiving in a "live" stage of studio.mjs (see the screenshots `shots`): the plots
    and the state panel draw new coloured pixels (series, state bar) in 2.5 s; the raw-message panels show a new
    message; the log panel the session's state changes; the 3D panel the end effector (pixels of its colour
    inside the panel)."""
    px = live["pixels"]
    for pid in layout["configById"]:
        kind = pid.split("!")[0]
        a, b = live["first"][pid]["text"], live["second"][pid]["text"]
        if kind in ("Plot", "StateTransitions"):
            assert px[pid]["changed_colour"] >= 30, (pid, px[pid], f"see {shots}")
        elif kind == "RawMessages":
            assert "Waiting for next message" not in b and re.search(r"@ \d+\.\d+ sec", b), (pid, b)
            assert a != b, (pid, "no new message in 2.5 s")
        elif kind in ("RosOut", "Log"):
            assert "ALIGNING -> ENABLED" in " ".join(b.split()), (pid, b)
        elif kind == "3D":
            assert px[pid]["ee"] >= 20, (pid, px[pid], f"see {shots}")
        else:
            raise AssertionError(f"{pid}: a panel type this test does not know how to check")


def check_connected_without_problems(live: dict) -> None:
    """Connected, and no problems listed (the data source's Problems tab; no panel saying it cannot show)."""
    assert live["connected"], live["sidebar"]
    assert "No problems found" in live["sidebar"], live["sidebar"]
    for pid, p in live["second"].items():
        assert p["found"], pid
        assert not re.search(r"Unknown panel type|Failed to parse|[Ee]rror", p["text"]), (pid, p["text"])


def test_studio_shows_the_live_session_and_its_recording(tmp_path):
    assert (HERE / "node_modules" / "@foxglove" / "studio-base" / "assets" / "index.js").exists(), \
        "run `npm ci --prefix tests/browser` (scripts/install-system-deps.sh does)"
    layout = json.loads(LAYOUT.read_text())
    mcap = tmp_path / "session.mcap"
    cfg = {"chromium": CHROMIUM, "out": str(tmp_path), "layout": str(LAYOUT), "layout_fbg": str(LAYOUT_FBG),
           "fault_wait_s": FAULT_WAIT_S,
           "ee_rgb": rgb(EE_COLOR), "ee_fault_rgb": rgb(EE_FAULT_COLOR), "timeout_s": 60}
    (tmp_path / "studio.json").write_text(json.dumps(cfg))
    stages, proc, fbg = {}, None, None
    # the browser loads Studio while the session starts
    driver = subprocess.Popen([NODE, str(HERE / "studio.mjs"), str(tmp_path / "studio.json")], cwd=HERE,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def until(stage):
        for line in driver.stdout:
            rep = json.loads(line)
            stages[rep["stage"]] = rep
            if rep["stage"] == stage:
                return
        raise AssertionError(f"studio.mjs ended before stage {stage}: {driver.stderr.read()}")

    try:
        proc, port = start_session(tmp_path, SESSION_S, "--no-realtime", "--stale-ms", str(STALE_MS),
                                   "--record", str(tmp_path / "session.mcap"))
        robot = robot_process(proc.pid, port, mcap)
        until("ready")
        assert stages["ready"]["host_error"] is None, stages["ready"]
        driver.stdin.write(f"live ws://127.0.0.1:{port} {robot}\n")
        driver.stdin.flush()
        until("fault")
        # the session with FBG sensors starts while the first one closes and Studio opens its recording
        (tmp_path / "fbg").mkdir()
        fbg = spawn_session(tmp_path / "fbg", SESSION_S, "--no-realtime", "--stale-ms", str(STALE_MS),
                            "--robot", "sim://robot?sensor=fbg")
        # the session is stopped as an operator would (SIGTERM: the recording closed whole, docs/safety.md)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(60) == 128 + signal.SIGTERM, proc.stderr.read()
        driver.stdin.write(f"recording {mcap}\n")
        driver.stdin.flush()
        rec = read_session(mcap)  # while Studio opens it
        assert rec.complete and rec.is_intact, rec.damage
        # then Studio shows the FBG session with the FBG layout
        driver.stdin.write(f"live-fbg ws://127.0.0.1:{served_port(fbg)}\n")
        driver.stdin.flush()
        until("live_fbg")
        fbg.send_signal(signal.SIGTERM)
        assert fbg.wait(60) == 128 + signal.SIGTERM, fbg.stderr.read()
        out, err = driver.communicate(timeout=120)
        for line in out.splitlines():
            rep = json.loads(line)
            stages[rep["stage"]] = rep
        assert driver.returncode == 0, err
    finally:  # SIGTERM first: puppeteer closes the browser it launched (in its own process group) on it
        for p in (proc, fbg, driver):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait(10)
        (tmp_path / "studio-report.json").write_text(json.dumps(stages, indent=1))  # what was seen, if a step failed
    live, fault, recording = stages["live"], stages["fault"], stages.get("recording")
    session = json.loads((tmp_path / "session.json").read_text())

    check_connected_without_problems(live)
    check_every_panel_receiving(layout, live, f"{tmp_path}/live-1.png, live.png")

    # the induced fault: a FAULT line in the log panel, with the reason the session reported
    reasons = [e.get("reason", "") for e in session["events"] if e.get("dst") == "FAULT"]
    assert reasons and "robot telemetry stale" in reasons[0], session["events"]
    assert fault["found"], (fault["log_panels"], f"see {tmp_path}/fault.png")
    log_text = "\n".join(p["text"] for p in fault["log_panels"].values())
    assert f"-> FAULT: {reasons[0]}" in " ".join(log_text.split()), log_text
    assert "No problems found" in fault["sidebar"], fault["sidebar"]

    # the recording opens in the same page: no problems, every topic listed with the project's reader's count
    assert recording is not None and recording["opened"], recording
    assert "No problems found" in recording["sidebar"], recording["sidebar"]
    counts = Counter(tp for tp, _, _, _ in rec.records) + Counter(rec.views)
    assert {tp: shown_count(tp, recording["topics"]) for tp in counts} == dict(counts), recording["topics"]

    # the session with FBG sensors in the FBG layout: every panel receiving, the FBG panel among them
    layout_fbg = json.loads(LAYOUT_FBG.read_text())
    assert "Plot!fbg" in layout_fbg["configById"] and "Plot!fbg" not in layout["configById"]
    check_connected_without_problems(stages["live_fbg"])
    check_every_panel_receiving(layout_fbg, stages["live_fbg"], f"{tmp_path}/live-fbg-1.png, live-fbg.png")
