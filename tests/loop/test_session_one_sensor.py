"""Seed 001's one-sensor mode (`sim://robot?sensor=one`) in a live session: the rest identification at start-up
(teleop.core.estimation.sensor_reading) lets the robot enable and render a contact force; the recording holds
the FBG channel (teleop.io.recording.sensors) with a schema its messages validate against.

Without the rest identification eq 7 starts every modelled cable on its lower line (Kp Fp, 0.83 x the 2.85 N
pretension) while the FBG reads the cable's neutral 2.85 N: a phantom force of about 0.4 N keeps the session in
ALIGNING."""

import json

import numpy as np
import pytest
from mcap.reader import make_reader

from devices.base import RobotReading
from teleop.apps.cli import main
from teleop.io.recording import TOPIC_FORCE, TOPIC_ROBOT, read_session
from teleop.io.recording.sensors import TOPIC_FBG
from teleop.loop.devices_by_url import open_device
from teleop.loop.session import loop_estimator
from tests.io.recording._schemas import check_channel

URL = "sim://robot?sensor=one&seed=3"
STYLUS = "sim://?script=pokes&seed=3"  # the session default: the tool reaches the pad at about 0.4 s


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    d = tmp_path_factory.mktemp("one")
    rec, js = d / "one.mcap", d / "one.json"
    assert main(["session", "--haptic", STYLUS, "--robot", URL, "--seconds", "1", "--robot-inline", "--sim-clock",
                 "--record", str(rec), "--json", str(js)]) == 0
    return rec, json.loads(js.read_text())


def test_one_sensor_session_enables_at_once_and_renders_contact(session, capsys):
    rec, res = session
    capsys.readouterr()
    enabled = [e for e in res["events"] if e["dst"] == "ENABLED"]
    assert enabled and enabled[0]["t"] < 0.1, res["events"]
    assert res["final_state"] == "ENABLED" and not res["fault_reason"]
    s = read_session(str(rec))
    truth = np.array([m["wrench_truth"][2] for m in s.messages(TOPIC_ROBOT)])
    cf = np.array([m["servo_cf"][2] for m in s.messages(TOPIC_FORCE)])
    assert truth.min() < -0.3  # the stylus pressed the robot's tool into the pad
    assert np.abs(cf).max() > 0.3  # and the operator felt it


def test_recording_holds_the_fbg_channel_with_its_schema(session):
    rec, _ = session
    with open(rec, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        ch = next(c for c in summary.channels.values() if c.topic == TOPIC_FBG)
        payloads = [m.data for _, c, m in reader.iter_messages(topics=[TOPIC_FBG])]
    assert check_channel(summary.schemas[ch.schema_id].data, payloads, TOPIC_FBG) >= 990
    msgs = [json.loads(p) for p in payloads]
    assert all(m["fbg_cable"] == 0 for m in msgs)  # one cable: a number
    rest = [m["rest"] for m in msgs]
    assert rest[0] == 1 and rest[-1] == 0 and sorted(rest, reverse=True) == rest  # at rest until the robot moved
    assert 0.8 < msgs[-1]["rest_ratio"] < 1.25 and 1.0 < msgs[0]["fbg_force"] < 5.0
    assert len(msgs[0]["proximal"]) == 6


def test_rest_identification_reads_the_modelled_cables_at_rest():
    """At rest (neutral sheaths: distal = proximal = pretension) every cable's estimate is its true tension."""
    est = loop_estimator(URL, 1e-3)
    robot = open_device(URL)
    with robot:
        for _ in range(200):
            r = robot.read()
            t, _ = est.update(r, np.r_[robot.pose], 1e-3)
        truth = r.extras["t_tip"]
    assert est.at_rest
    # the modelled cables from the means over the rest readings; cable 0 is one FBG reading (0.075 N noise)
    assert np.abs(t[1:] - truth[1:]).max() < 0.05 and abs(t[0] - truth[0]) < 0.3, (t, truth)
    # a moved robot ends it: eq 7 runs on from the rest state
    moved = RobotReading(**{**vars(r), "commanded_lengths": r.commanded_lengths + 1e-4})
    est.update(moved, robot.pose, 1e-3)
    assert not est.at_rest
