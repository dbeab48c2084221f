"""`teleop replay` of sessions with the FBG sensor kinds (`sim://robot?sensor=fbg|one`): the estimator is rebuilt
from the recording and the recorded Bragg shifts (/sensors/fbg) go through it again, reproducing the recorded
estimate (tensions and wrench on /estimation) and everything after it.

Tolerance: none (bit for bit). The recording's floats are written bit-exact (shortest round-trip JSON) and the
estimator is a deterministic function of the recorded readings and tick times, run by the same compiled
kernels; a difference of one ulp is a replay that does not reproduce, so the test asserts equality.
"""

import json

import numpy as np
import pytest

from teleop.apps.cli import main
from teleop.core.errors import InputError
from teleop.core.sensors import FbgParams
from teleop.io.recording import read_session
from teleop.io.recording.sensors import TOPIC_FBG
from teleop.loop.replay import replay_session

STYLUS = "sim://?script=pokes&seed=3"  # the session default: the tool reaches the pad at about 0.4 s
SECONDS = 1.5


@pytest.fixture(scope="module", params=["fbg", "one"])
def recorded(request, tmp_path_factory):
    kind = request.param
    d = tmp_path_factory.mktemp(kind)
    rec = d / f"{kind}.mcap"
    assert main(["session", "--haptic", STYLUS, "--robot", f"sim://robot?sensor={kind}&seed=3", "--seconds",
                 str(SECONDS), "--robot-inline", "--sim-clock", "--record", str(rec)]) == 0
    return kind, rec


def test_replay_reproduces_the_recorded_estimate(recorded, capsys, tmp_path):
    kind, rec = recorded
    s = read_session(rec)
    assert s.metadata["session"]["calibration"]["sensor"] == kind
    wrench = s.array("/estimation", "measured_cf")
    assert np.abs(wrench[:, :3]).max() > 0.3  # a contact force was estimated, not a wrench of zeros
    fbg = s.messages(TOPIC_FBG)
    assert len(fbg) == len(s.messages("/loop")) == int(SECONDS * 1000)
    capsys.readouterr()
    out = tmp_path / "replay.json"
    assert main(["replay", str(rec), "--json", str(out)]) == 0
    assert "reproduced" in capsys.readouterr().out
    rep = json.loads(out.read_text())
    assert rep["reproduced"] and rep["ticks"] == len(fbg)
    assert rep["estimate_mismatches"] == 0 and rep["max_wrench_diff"] == 0.0 and rep["max_force_diff"] == 0.0


def test_replay_feeds_the_recorded_fbg_shifts(recorded):
    """One recorded FBG2 shift raised by the sensitivity S (1 N of tension on that cable, at one tick in contact)
    changes the replayed estimate from that tick on: the replay reads the shifts, it does not copy the estimate."""
    kind, rec = recorded
    s = read_session(rec)
    msgs = s.messages(TOPIC_FBG)
    m = msgs[len(msgs) * 2 // 3]
    dl2 = m["fbg_dl2_pm"]
    if isinstance(dl2, list):
        dl2[0] += FbgParams().S_pm_N
    else:  # one instrumented cable: a number
        m["fbg_dl2_pm"] = dl2 + FbgParams().S_pm_N
    rep = replay_session(str(rec), session=s)
    assert not rep.reproduced and rep.estimate_mismatches > 0 and rep.max_wrench_diff > 0.01


def test_unreplayable_fbg_recordings_say_why(recorded):
    kind, rec = recorded
    s = read_session(rec)
    s.records = [r for r in s.records if r[0] != TOPIC_FBG]  # an FBG session whose shifts were not recorded
    with pytest.raises(InputError, match=f"no {TOPIC_FBG} messages"):
        replay_session(str(rec), session=s)
    s = read_session(rec)
    del s.metadata["session"]["calibration"]["fbg"]
    with pytest.raises(InputError, match="FBG estimator settings not understood"):
        replay_session(str(rec), session=s)


def test_a_recording_cut_before_its_last_fbg_message_replays_its_whole_ticks(recorded):
    """The FBG channel is the last of a tick's row: a file cut between a tick's wrench and its FBG message
    replays up to the tick before, and that prefix reproduces."""
    kind, rec = recorded
    s = read_session(rec)
    last = max(i for i, r in enumerate(s.records) if r[0] == TOPIC_FBG)
    s.records = s.records[:last]
    rep = replay_session(str(rec), session=s)
    assert rep.reproduced and rep.ticks == len(s.messages("/loop")) - 1
