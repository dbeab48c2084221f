"""Issue 29 item 8: an effect-free session of the project's own simulated robot, exported and diagnosed, gets
no finding on the sheath's link (the force link: the simulation's tension at the FSR from the tip tension,
the sheath's capstan the baseline), over several seeds and session lengths; the baseline fits it to the
simulation's numerical precision. Sessions as `teleop bench session-diagnose` makes them (simulated clock,
the simulated operator's pokes), without any effect switched on."""

import subprocess
import sys

import pytest

from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange

SCRIPT = "sim://?script=pokes&depth_mm=10&period_s=2&seed={seed}"
SESSIONS = [(1, 6.0), (2, 10.0), (3, 8.0)]


def _teleop(*args):
    res = subprocess.run([sys.executable, "-m", "teleop.apps.cli", *args], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-800:]


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    out = {}
    for seed, seconds in SESSIONS:
        work = tmp_path_factory.mktemp(f"s{seed}")
        mcap, csv = work / "session.mcap", work / "cable1.csv"
        _teleop("session", "--haptic", SCRIPT.format(seed=seed), "--robot", f"sim://robot?seed={seed}",
                "--seconds", str(seconds), "--robot-inline", "--sim-clock", "--record", str(mcap))
        _teleop("export", str(mcap), "--csv", str(csv), "--cable", "1", "--truth")
        out[(seed, seconds)] = diagnose(read_interchange(csv))
    return out


@pytest.mark.parametrize("seed, seconds", SESSIONS)
def test_effect_free_session_no_finding_on_the_sheath(sessions, seed, seconds):
    diag = sessions[(seed, seconds)]
    doc = diag.as_dict()
    assert [f for f in doc["findings"] if f["channel"] == "motor_force"] == []
    assert doc["baseline"]["effects"]["motor_force"] == ["capstan_friction"]
    force = next(res for res in diag.links if res.data.link.kind == "force")
    # the simulation's own law: the baseline reproduces the FSR tension to a micro-newton (it was 1 mN, its
    # switch a sample late at each reversal)
    assert force.baseline.rmse_hold < 1e-5, force.baseline.rmse_hold
    assert not [u for u in doc["unexplained"] if u["channel"] == "motor_force"]


@pytest.mark.xfail(strict=True, reason="the export's tip_pos is the contact tip's pose, a 10 g mass on the series "
                   "spring behind the commanded tip: a real ~1.4 ms first-order lag the rigid position link lacks; "
                   "the export (not the diagnosis) must declare it or read the cable's own end (issue 29 item 8)")
def test_effect_free_session_no_finding_anywhere(sessions):
    assert all(diag.as_dict()["findings"] == [] for diag in sessions.values())
