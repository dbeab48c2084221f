"""`actuator_pos`: the actuator's own position where motor_pos is measured past a gearbox or coupling drives
the force link's friction laws (the proximal force sensor sits between actuator and motor_pos), while the
position link stays motor_pos -> tip_pos. Generated from the physics models only: a spindle that follows its
motor through a coupling play, a Dahl friction that follows the motor."""

import numpy as np

from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.links import find_links
from teleop.io.recording_io import read_interchange, write_interchange
from teleop.core.physics import backlash, dahl


def _recording(tmp_path, with_actuator: bool):
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 20.0, 1e-3)
    act = np.radians(30.0) * np.sin(2 * np.pi * 0.3 * t)           # motor angle [rad]
    spindle = backlash(act, np.radians(4.0))                         # the spindle past a coupling play
    jaw = -0.9 * spindle + 0.02 * np.sin(0.7 * t)                   # jaw angle (and a slow wobble)
    tip_torque = 0.05 + 0.02 * np.sin(2 * np.pi * 0.11 * t)          # reaction torque [N m]
    torque = 1.3 * tip_torque + dahl(act, 2.0, 0.04)                 # friction follows the motor
    ch = {"motor_pos": spindle, "tip_pos": jaw + rng.normal(0, 2e-4, t.size),
          "motor_force": torque + rng.normal(0, 3e-4, t.size), "tip_force": tip_torque + rng.normal(0, 3e-4, t.size)}
    units = {"motor_pos": "rad", "tip_pos": "rad", "motor_force": "N m", "tip_force": "N m"}
    if with_actuator:
        ch["actuator_pos"], units["actuator_pos"] = act, "rad"
    path = tmp_path / ("with.csv" if with_actuator else "without.csv")
    write_interchange(path, t, ch, units, {"load": "external"})
    return read_interchange(path)


def test_the_force_link_follows_the_actuator_and_finds_its_friction(tmp_path):
    rec = _recording(tmp_path, True)
    links = {link.kind: link for link in find_links(rec)}
    assert links["force"].drive == "actuator_pos" and links["position"].input == "motor_pos"
    doc = diagnose(rec).as_dict()
    force = [f for f in doc["findings"] if f["channel"] == "motor_force"]
    assert force and force[0]["effect"] == "dahl_hysteresis", doc["findings"]
    assert abs(force[0]["params"]["Fc"]["value"] - 0.04) < 0.2 * 0.04
    # driven by the spindle (past the play), the same friction fits clearly worse: it reverses a play late
    without = diagnose(_recording(tmp_path, False)).as_dict()
    rmse = {d["recording"]: d["channels"]["motor_force"]["rmse_model"] for d in (doc, without)}
    assert doc["channels"]["motor_force"]["rmse_model"] < 0.5 * without["channels"]["motor_force"]["rmse_model"], rmse
