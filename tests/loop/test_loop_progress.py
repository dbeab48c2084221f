"""Progress of `teleop session` and `teleop bench loop` (teleop.loop.loop_progress): ticks, state, deadline
misses and faults; a plain line every few seconds off a terminal (on a controlled clock here), a tqdm bar on
one, and the session command's own stderr."""

import io
import subprocess
import sys
from types import SimpleNamespace

import numpy as np

from teleop.io.progress import PlainProgress, progress
from teleop.loop.core import STAGES
from teleop.loop.loop_progress import CHECK_EVERY, LoopProgress
from teleop.loop.states import State
from teleop.loop.timing import TimingLog


class Clock:
    def __init__(self):
        self.t = 50.0

    def __call__(self):
        return self.t


def _run(lp, tp, log, clock, ticks, late_every=0, fault_at=None):
    for k in range(ticks):
        late = 600_000 if late_every and k % late_every == 0 else 1_000  # 0.6 ms: a miss at 1 kHz
        log.add(late, 5_000, np.zeros(len(STAGES)))
        if k == fault_at:
            tp.state = State.FAULT
            tp.events.append(SimpleNamespace(dst="FAULT"))
        clock.t += 1e-3
        lp.on_tick(k, late)


def test_plain_lines_name_ticks_state_misses_and_faults():
    clock, out = Clock(), io.StringIO()
    tp = SimpleNamespace(state=State.ENABLED, events=[])
    log = TimingLog(20_000)
    bar = PlainProgress(20_000, "session", "ticks", stream=out, interval_s=5.0, clock=clock, start_line=True)
    lp = LoopProgress(tp, log, 20_000, 1000.0, bar=bar)
    _run(lp, tp, log, clock, 12_000, late_every=1000, fault_at=11_000)
    lp.close()
    lines = out.getvalue().splitlines()
    assert lines[0] == "session: 0/20000 ticks (0 %), 0 s elapsed"  # at once: the run is alive
    # every 5 s of the clock, counted at the loop's looks (every CHECK_EVERY ticks)
    assert lines[1] == f"session: {5000 + 1}/20000 ticks (25 %), 5 s elapsed, about 15 s left, ENABLED, " \
                       f"6 misses, 0 faults"
    assert lines[2].startswith("session: 10") and " ticks (5" in lines[2] and "10 s elapsed" in lines[2]
    assert lines[2].endswith("ENABLED, 11 misses, 0 faults")
    assert lines[-1] == "session: done, 12000 ticks in 12 s, FAULT, 12 misses, 1 faults"
    assert CHECK_EVERY <= 1000


def test_a_terminal_gets_a_bar_with_the_state():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    out = Tty()
    clock = Clock()
    tp = SimpleNamespace(state=State.ENABLED, events=[])
    log = TimingLog(2_000)
    lp = LoopProgress(tp, log, 2_000, 1000.0, bar=progress(2_000, "session", unit="ticks", stream=out,
                                                             mininterval=0))
    _run(lp, tp, log, clock, 2_000, late_every=500)
    lp.close()
    text = out.getvalue()
    assert "2000/2000" in text and "ENABLED, 4 misses, 0 faults" in text


def test_teleop_session_shows_its_progress_off_a_terminal():
    r = subprocess.run([sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "2", "--sim-clock",
                        "--robot-inline"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("session: ")]
    assert lines[0] == "session: 0/2000 ticks (0 %), 0 s elapsed"
    assert lines[-1].startswith("session: done, 2000 ticks in ") and lines[-1].endswith(", 0 faults")
