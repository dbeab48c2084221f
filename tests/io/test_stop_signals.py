"""SIGTERM, SIGINT and SIGHUP end a long command as Ctrl-C does (docs/safety.md): sent to the process or to its
whole group (the recorder, robot and live-view processes get it too), once or repeated, a session stops its
loop, writes its JSON marked with the signal's name, closes its recording whole and exits 128 + the number.
Other commands get a KeyboardInterrupt (teleop.io.stop_signals) and exit the same way."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from teleop.io.recording import read_session
from teleop.io.stop_signals import STOP, STOP_SIGNALS, Stop, exit_code

CASES = [  # (signal, to the group?, times sent, extra session arguments)
    (signal.SIGTERM, False, 1, []),
    (signal.SIGTERM, True, 1, ["--live", "0"]),
    (signal.SIGINT, True, 1, []),
    (signal.SIGINT, False, 3, []),
    (signal.SIGHUP, True, 2, []),
]


def _start_session(tmp_path, extra):
    argv = [sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "120", "--no-realtime",
            "--json", str(tmp_path / "s.json"), "--record", str(tmp_path / "s.mcap"), *extra]
    err = open(tmp_path / "err.txt", "w")
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    deadline = time.monotonic() + 120
    while "ticks (0 %)" not in (tmp_path / "err.txt").read_text():  # the loop's progress: it is running
        assert proc.poll() is None and time.monotonic() < deadline, (tmp_path / "err.txt").read_text()
        time.sleep(0.1)
    time.sleep(1.0)
    return proc


@pytest.mark.parametrize("sig, group, times, extra", CASES,
                         ids=[f"{c[0].name}-{'group' if c[1] else 'process'}-x{c[2]}" for c in CASES])
def test_a_signal_ends_a_session_as_ctrl_c_does(tmp_path, sig, group, times, extra):
    proc = _start_session(tmp_path, extra)
    for _ in range(times):
        if group:
            os.killpg(proc.pid, sig)
        else:
            os.kill(proc.pid, sig)
        time.sleep(0.05)
    rc = proc.wait(60)
    err = (tmp_path / "err.txt").read_text()
    assert rc == 128 + sig, err
    out = json.loads((tmp_path / "s.json").read_text())
    assert out["interrupted"] == sig.name
    assert 0 < out["timing"]["ticks"] < 120_000
    s = read_session(tmp_path / "s.mcap")
    assert s.complete and s.is_intact, s.damage
    assert s.metadata["session_end"]["interrupted"] == sig.name
    assert len(s.messages("/loop")) > 0
    assert f"interrupted ({sig.name})" in err


def test_a_session_that_runs_its_length_is_not_interrupted(tmp_path):
    out = tmp_path / "s.json"
    r = subprocess.run([sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "0.5", "--no-realtime",
                        "--robot-inline", "--json", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(out.read_text())["interrupted"] is False


def test_a_command_that_does_not_poll_gets_keyboard_interrupt():
    stop = Stop()
    stop.install()
    try:
        with pytest.raises(KeyboardInterrupt):
            stop.handle(signal.SIGTERM)
        assert stop.name == "SIGTERM"
        stop.handle(signal.SIGINT)  # a repeat: no second interruption of the clean-up, the first name kept
        assert (stop.name, stop.count) == ("SIGTERM", 2)
    finally:
        stop.uninstall()


def test_a_polling_loop_only_sees_the_flag():
    stop = Stop()
    with stop.polled():
        stop.handle(signal.SIGHUP)  # no exception mid-tick
    assert stop.requested() and exit_code(stop.signum) == 129


def test_a_forked_child_ignores_the_handler():
    stop = Stop()
    stop.pid = os.getpid() + 1  # as seen from a child forked after install
    stop.handle(signal.SIGTERM)
    assert not stop.requested()


def test_blind_test_ends_on_sigterm_with_143(tmp_path):
    err = open(tmp_path / "err.txt", "w")
    proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "blind-test", "--participants", "50"],
                            stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    deadline = time.monotonic() + 120
    while "blind test: 0/50" not in (tmp_path / "err.txt").read_text():
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGTERM)
    assert proc.wait(60) == 143
    assert "teleop: interrupted (SIGTERM)" in (tmp_path / "err.txt").read_text()
    assert STOP.signum == 0  # this process's own request untouched


def test_sighup_with_the_terminal_gone_still_writes_the_json_and_closes_the_recording(tmp_path):
    """A closed terminal: every print fails (here: pipes whose reader is gone), then SIGHUP to the group."""
    argv = [sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "120", "--no-realtime",
            "--json", str(tmp_path / "s.json"), "--record", str(tmp_path / "s.mcap")]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    while "ticks (0 %)" not in proc.stderr.readline():
        assert proc.poll() is None
    time.sleep(1.0)
    proc.stdout.close()
    proc.stderr.close()
    time.sleep(1.0)  # the progress writes fail meanwhile: the loop goes on
    os.killpg(proc.pid, signal.SIGHUP)
    assert proc.wait(60) == 129
    assert json.loads((tmp_path / "s.json").read_text())["interrupted"] == "SIGHUP"
    s = read_session(tmp_path / "s.mcap")
    assert s.complete and s.is_intact and s.metadata["session_end"]["interrupted"] == "SIGHUP"


def test_sigterm_ends_bench_loop_with_its_json_marked(tmp_path):
    err = open(tmp_path / "err.txt", "w")
    proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "bench", "loop", "--seconds", "120",
                             "--no-realtime", "--json", str(tmp_path / "b.json")],
                            stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    deadline = time.monotonic() + 120
    while "bench loop 1000 Hz: 0/120000 ticks" not in (tmp_path / "err.txt").read_text():
        assert proc.poll() is None and time.monotonic() < deadline, (tmp_path / "err.txt").read_text()
        time.sleep(0.1)
    time.sleep(1.0)
    os.killpg(proc.pid, signal.SIGTERM)
    assert proc.wait(60) == 143
    out = json.loads((tmp_path / "b.json").read_text())
    assert out["interrupted"] == "SIGTERM" and 0 < out["ticks"] < 120_000


def test_a_stopped_command_ignores_the_repeats_once_its_handler_is_gone():
    """uninstall(ignore=True) puts SIG_IGN in place of the handler in one step (no default handler between,
    which killed a session the second SIGHUP of `kill -HUP` twice reached while it returned); without it the
    handlers from before install come back."""
    before = {s: signal.getsignal(s) for s in STOP_SIGNALS}
    stop = Stop()
    stop.install()
    stop.uninstall(ignore=True)
    try:
        assert all(signal.getsignal(s) is signal.SIG_IGN for s in STOP_SIGNALS)
    finally:
        for s, h in before.items():
            signal.signal(s, h)
    stop.install()
    stop.uninstall()
    assert {s: signal.getsignal(s) for s in STOP_SIGNALS} == before
