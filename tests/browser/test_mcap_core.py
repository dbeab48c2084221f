"""Every kind of recording the project writes, read by a reader it did not write: @mcap/core 2.2.2 in node
(tests/browser/mcap_read.mjs), CRCs checked (every chunk's, the summary's, the data section's), message counts
per topic equal to the project's own reader's (teleop.io.recording.read_session: its messages plus the
Foxglove views it leaves to Foxglove).

Kinds: a paced session (robot in its own process), a session on the simulated clock (robot inline, a sensor
variant that adds robot extras), `teleop bench loop --record`, a session whose every process was SIGKILLed
(the streaming reader recovers exactly the intact prefix), the same recording cut at more byte offsets, and
what `teleop recover` makes of the killed one (complete and indexed).

Needs node (scripts/install-system-deps.sh; `npm ci --prefix tests/browser`); skipped only when it is missing.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest

from teleop.io.recording import read_session

HERE = Path(__file__).resolve().parent
NODE = shutil.which("node")

pytestmark = pytest.mark.skipif(NODE is None, reason="needs node (scripts/install-system-deps.sh)")


def teleop(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", *map(str, args)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def finished(*procs) -> None:
    for p in procs:
        _, err = p.communicate(timeout=300)
        assert p.returncode == 0, (p.args, err)


def mcap_core(*paths) -> dict:
    """{path: report} from @mcap/core (mcap_read.mjs)."""
    assert (HERE / "node_modules" / "@mcap" / "core").exists(), \
        "run `npm ci --prefix tests/browser` (scripts/install-system-deps.sh does)"
    r = subprocess.run([NODE, str(HERE / "mcap_read.mjs"), *map(str, paths)], capture_output=True, text=True,
                       timeout=300, cwd=HERE)
    assert r.returncode == 0, r.stderr
    reps = [json.loads(line) for line in r.stdout.splitlines()]
    return {rep["path"]: rep for rep in reps}


def project_counts(path) -> tuple[dict, object]:
    s = read_session(path)
    return dict(Counter(tp for tp, _, _, _ in s.records) + Counter(s.views)), s


def killed_session(tmp_path: Path) -> Path:
    """A paced session whose every process (loop, robot, recorder) is SIGKILLed mid-run."""
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "session", "--seconds", "60", "--no-realtime",
                             "--record", str(path)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and (not path.exists() or path.stat().st_size < 200_000):
            assert proc.poll() is None, proc.stderr.read()
            time.sleep(0.2)
        time.sleep(1.0)  # more flushed chunks, and the recorder mid-way through the next
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)
    assert path.stat().st_size >= 200_000
    return path


def test_mcap_core_reads_every_kind_of_recording(tmp_path):
    paced, simclock, bench = tmp_path / "paced.mcap", tmp_path / "simclock.mcap", tmp_path / "bench.mcap"
    runs = [teleop("session", "--seconds", 2, "--no-realtime", "--record", paced),
            teleop("session", "--seconds", 2, "--sim-clock", "--robot-inline", "--robot",
                   "sim://robot?sensor=one&cable=2", "--record", simclock),
            teleop("bench", "loop", "--seconds", 1, "--no-realtime", "--record", bench, "--json", tmp_path / "b.json")]
    killed = killed_session(tmp_path)
    fixed = tmp_path / "fixed.mcap"
    finished(teleop("recover", killed, "--out", fixed), *runs)
    data = killed.read_bytes()
    cuts = []
    for frac in (0.1, 0.37, 0.5, 0.81, 0.999):  # more crashes: the killed file cut shorter still
        cut = tmp_path / f"cut{int(frac * 1000):03d}.mcap"
        cut.write_bytes(data[:int(len(data) * frac)])
        cuts.append(cut)
    complete, unfinished = [paced, simclock, bench, fixed], [killed, *cuts]
    reps = mcap_core(*complete, *unfinished)
    (tmp_path / "mcap-core.json").write_text(json.dumps(reps, indent=1))

    for path in complete:
        rep, (counts, s) = reps[str(path)], project_counts(path)
        assert s.complete and s.is_intact, (path.name, s.damage)
        st, ix = rep["stream"], rep["indexed"]
        assert st["error"] is None and st["done"], (path.name, st)
        assert st["chunks"] > 0 and st["chunks_without_crc"] == 0, (path.name, st)  # every chunk's CRC checked
        assert st["counts"] == counts, (path.name, st["counts"], counts)
        assert ix is not None and ix["error"] is None, (path.name, ix)
        assert ix["data_crc"]["ok"], (path.name, ix["data_crc"])
        assert ix["counts"] == counts, (path.name, ix["counts"], counts)
        assert ix["statistics"] == {"message_count": sum(counts.values()), "counts": counts}, (path.name, ix)
        assert sorted(ix["metadata"]) == sorted(st["metadata"]) == sorted(s.metadata), (path.name, ix["metadata"])
        # closed by the session itself: its end record; what `teleop recover` rebuilt: says so instead
        assert {"session", "recovered" if path == fixed else "session_end"} <= set(s.metadata), (path.name, s.metadata)

    for path in unfinished:  # the streaming reader: every message of the intact prefix, and nothing else
        rep, (counts, s) = reps[str(path)], project_counts(path)
        assert not s.complete, path.name
        st = rep["stream"]
        assert st["error"] is None and not st["done"] and st["chunks_without_crc"] == 0, (path.name, st)
        assert st["counts"] == counts, (path.name, st["counts"], counts)
    assert sum(project_counts(killed)[0].values()) > 0
    # what `teleop recover` wrote holds every message the killed recording had flushed
    assert reps[str(fixed)]["indexed"]["counts"] == reps[str(killed)]["stream"]["counts"]
