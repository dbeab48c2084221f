"""Structured residual that no catalogued effect explains is reported as `unexplained` with its best
correlate, and no wrong name is forced; a spring-loaded rig without a tip force sensor still works."""

import numpy as np

from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, write_interchange
from teleop.core.physics import Signals, get_effect

UNITS = {"motor_pos": "m", "motor_force": "N", "tip_force": "N", "tip_pos": "m"}


def _rig(tmp_path, motor_force, x, load, meta, extra=None):
    chans = {"motor_pos": x, "motor_force": motor_force}
    if load is not None:
        chans["tip_force"] = load
    chans.update(extra or {})
    path = write_interchange(tmp_path / "r.csv", np.arange(x.size) * 2e-3, chans, UNITS, meta)
    return diagnose(read_interchange(path)).as_dict()


def test_cogging_ripple_is_unexplained_not_misnamed(tmp_path):
    rng = np.random.default_rng(3)
    t = np.arange(0, 20, 2e-3)
    x = 5e-3 * np.sin(2 * np.pi * 0.4 * t) + 2e-3 * np.sin(2 * np.pi * 0.23 * t)
    load = 10 + 3 * np.sin(2 * np.pi * 0.11 * t)
    ripple = 0.8 * np.sin(2 * np.pi * x / 2e-3)            # periodic in motor position, period 2 mm
    fm = 1.02 * load + 0.3 + ripple + rng.normal(0, 0.05, t.size)
    doc = _rig(tmp_path, fm, x, load + rng.normal(0, 0.05, t.size), {"load": "external"})
    assert doc["findings"] == []
    (u,) = doc["unexplained"]
    assert u["channel"] == "motor_force" and u["correlate"] == "periodic in position" and u["r2"] > 0.8


def test_spring_load_without_tip_sensor(tmp_path):
    rng = np.random.default_rng(4)
    t = np.arange(0, 20, 2e-3)
    x = 6e-3 * np.sin(2 * np.pi * 0.3 * t) + 2e-3 * np.sin(2 * np.pi * 0.71 * t)
    tip = 0.95 * x + 1e-4
    spring = 800.0 * (tip + 8e-3)                         # N, the spring the cable pulls
    fm = get_effect("coulomb_friction").apply(Signals(t=t, x=x, load=spring), {"Fc": 0.6})
    doc = _rig(tmp_path, fm + rng.normal(0, 0.03, t.size), x, None, {"load": "spring"},
               {"tip_pos": tip + rng.normal(0, 2e-6, t.size)})
    force = [f for f in doc["findings"] if f["channel"] == "motor_force"]
    assert force and force[0]["effect"] == "coulomb_friction"
    assert abs(force[0]["params"]["Fc"]["value"] - 0.6) < 0.12
    assert doc["channels"]["motor_force"]["input"] == "tip_pos"


def test_pure_delay_is_named_a_delay_not_backlash(tmp_path):
    rng = np.random.default_rng(5)
    t = np.arange(0, 20, 2e-3)

    def motion(tt):
        return 5e-3 * np.sin(2 * np.pi * 0.4 * tt) + 2e-3 * np.sin(2 * np.pi * 0.93 * tt)

    x, tip = motion(t), 0.95 * motion(t - 0.03)          # a 30 ms sensor delay, no play
    path = write_interchange(tmp_path / "d.csv", t, {"motor_pos": x + rng.normal(0, 2e-6, t.size),
                                                     "tip_pos": tip + rng.normal(0, 2e-6, t.size)},
                             UNITS, {})
    doc = diagnose(read_interchange(path)).as_dict()
    # a delay is in the catalogue (transport_delay): named, counted in the final fit, nothing left over
    assert [f["effect"] for f in doc["findings"]] == ["transport_delay"] and doc["unexplained"] == []
    assert abs(doc["findings"][0]["params"]["delay"]["value"] - 0.03) < 0.002
