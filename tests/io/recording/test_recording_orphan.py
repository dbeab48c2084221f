"""Only the loop (main) process of a recording session is killed: the recorder sees its parent die, drains
the ring and closes the file, and `session_end` holds the last state the rows carried and why it ended."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from teleop.io.recording import read_session
from teleop.io.recording.foxglove import STATE_NAMES
from tests.io.recording.test_recording_kill import SESSION, check_file


def test_main_process_killed_leaves_session_end(tmp_path):
    repo = str(Path(__file__).resolve().parents[3])
    path = tmp_path / "orphan.mcap"
    proc = subprocess.Popen([sys.executable, "-c", SESSION.format(repo=repo, path=str(path))],
                            start_new_session=True, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None and (not path.exists()
                                                                       or path.stat().st_size < 20000):
            time.sleep(0.01)
        assert proc.poll() is None and path.exists(), proc.stderr.read().decode() if proc.poll() else "slow start"
        os.kill(proc.pid, signal.SIGKILL)  # the loop process only; its recorder lives on
        proc.wait()
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not read_session(path).complete:
            time.sleep(0.1)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # whatever is left of the group
        except ProcessLookupError:
            pass
    s, ticks = check_file(path)
    assert s.complete and s.is_intact, s.damage
    end = s.metadata["session_end"]
    assert f"loop process {proc.pid} ended without closing the recording" in end["interrupted"]
    last = s.messages("/loop")[-1]
    assert end["final_state"] == STATE_NAMES[last["state"]] and end["t_last"] == last["t"]
    assert end["rows_written"] == len(ticks) and end["fault_reason"] == ""
