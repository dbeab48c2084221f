"""SIGKILL at random moments (docs/safety.md): every file stays readable, at most 0.5 s is lost, and the
surviving records are intact and in sequence. The recorder process is killed 24 times while a producer
feeds it rows 1 ms apart on their own clock (t = tick x 1 ms); the loss is counted in ticks from the ring's
counters (pushed, written, made durable), not timed. Then whole sessions (loop process and recorder
together) are killed: every file readable, intact and in sequence."""

import os
import signal
import subprocess
import sys
import textwrap
import time

from pathlib import Path

import numpy as np

from teleop.loop.tap import session_layout
from teleop.io.recording import Recorder, read_session
from teleop.io.recording.ring import DURABLE, HEAD, WRITTEN

META = {"configuration": {}, "calibration": {}, "firmware_version": "test", "software_version": "test"}
MAX_LOSS_S = 0.5
DT = 1e-3  # the producer's tick period on the rows' clock [s]
FLUSH_S = 0.1


def check_file(path):
    """Read a killed recording: readable, ticks in sequence from 0 with no gaps; returns (session, ticks)."""
    s = read_session(path)  # never raises on damage
    loop = s.messages("/loop")
    assert loop, s.damage
    ticks = [m["tick"] for m in loop]
    assert ticks == list(range(ticks[0], ticks[0] + len(ticks)))  # in sequence, no gaps
    for topic in ("/stylus", "/haptic/servo_cf"):
        assert [m["tick"] for m in s.messages(topic)] == ticks[:len(s.messages(topic))]
    return s, ticks


def test_sigkill_recorder_many_times(tmp_path):
    layout = session_layout()
    rng = np.random.default_rng(4)
    row = np.zeros(layout.width)
    sl = layout.slices()
    i_tick, i_t = sl[("/loop", "tick")][0], sl[("/loop", "t")][0]
    for trial in range(24):
        path = tmp_path / f"kill{trial}.mcap"
        rec = Recorder(path, layout, META, capacity=4096, flush_interval=FLUSH_S).start()
        while not path.exists() or path.stat().st_size == 0:
            time.sleep(0.002)
        rec.set_t0(time.time_ns())
        kill_at = int(rng.integers(120, 500))  # ticks
        for k in range(kill_at):
            row[i_tick], row[i_t] = k, k * DT
            row[sl[("/stylus", "measured_cp")][0]] = np.sin(k)
            assert rec.push(row)
            time.sleep(0.001)  # pacing only: nothing below depends on how long this took
        os.kill(rec.proc.pid, signal.SIGKILL)
        rec.proc.join()
        rec.proc = None
        c = rec.ring.ctrl  # the shared counters outlive the killed process
        s, ticks = check_file(path)
        assert not s.complete  # killed: no footer, yet readable
        assert ticks[0] == 0 and len(ticks) >= c[DURABLE]  # everything the recorder made durable survived
        assert c[WRITTEN] - c[DURABLE] <= FLUSH_S / DT + 1  # it flushes every 0.1 s of the rows' clock
        assert (c[HEAD] - len(ticks)) * DT <= MAX_LOSS_S  # lost ticks, counted: <= 0.5 s of session


SESSION = textwrap.dedent("""
    import sys
    sys.path.insert(0, {repo!r})
    from tests.devices._fakes import FakeRobot, LinearEstimator
    from teleop.loop.session import run_session
    run_session("sim://?script=pokes", "fake", 30.0, record={path!r}, robot=FakeRobot(),
                estimator=LinearEstimator(), robot_process_hz=None)
""")


def test_sigkill_whole_session(tmp_path):
    repo = str(Path(__file__).resolve().parents[3])   # the tests package: tests.devices._fakes
    rng = np.random.default_rng(5)
    for trial in range(2):
        path = tmp_path / f"session{trial}.mcap"
        proc = subprocess.Popen([sys.executable, "-c", SESSION.format(repo=repo, path=str(path))],
                                start_new_session=True, stderr=subprocess.PIPE)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not path.exists() or path.stat().st_size < 20000):
            time.sleep(0.01)
        time.sleep(float(rng.uniform(0.0, 0.8)))
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        time.sleep(0.2)  # an orphaned recorder would still be finishing; killpg took it too
        s, ticks = check_file(path)
        assert ticks[0] == 0 and not s.complete
