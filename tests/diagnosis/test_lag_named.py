"""Lags are catalogue effects (teleop/core/physics/lag.py): a recording whose only structure is a lag names it
first, the lag counted in the final fit (its channel at the noise floor, nothing left unexplained); beside
another effect both are named; a late tip-force sensor on a spring rig is a transport delay taken out of the
channel before the sheath's link reads it; an effect-free recording names nothing.

The rig recordings are the simulated single-cable bench's (scenes.cable_rig: the lags drawn by their own
Rules.draw) on a sum-of-sines drive: on a drive of one frequency the two lags are one (Rules.alike)."""

import numpy as np
import pytest

from scenes.cable_rig import COLUMNS, simulate
from teleop.core.physics import first_order_lag
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange, write_interchange

FS, SECONDS = 500.0, 20.0
TIP_NOISE_M = 5e-6           # the bench's tip encoder: 5 um of noise on a 1 um lattice
SPRING_NO_TIP = ("motor_pos_mm", "motor_force_N", "tip_force_N", "bend_angle_deg", "temperature_C")


def _drive(seed: int) -> np.ndarray:
    """Motor haul-in [m]: three sines of 0.15-0.8 Hz (seeded)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(FS * SECONDS)) / FS
    return sum(a * np.sin(2 * np.pi * f * t + p) for a, f, p in
               zip((4e-3, 2e-3, 1e-3), rng.uniform(0.15, 0.8, 3), rng.uniform(0, 2 * np.pi, 3)))


def _rig(tmp_path, seed, effects, columns=COLUMNS, load="external", drive=True):
    rig = simulate([seed, 26], effects, columns, load, given={"x": _drive(seed)} if drive else None)
    path = tmp_path / "rig.csv"
    rig.write(path)
    return rig, diagnose(read_interchange(path)).as_dict()


def _first(doc: dict) -> dict:
    """The first finding of each channel."""
    out = {}
    for f in doc["findings"]:
        out.setdefault(f["channel"], f)
    return out


@pytest.mark.parametrize("name, param, seed", [("transport_delay", "delay", 1), ("first_order_lag", "tau", 2)])
def test_a_lag_alone_is_named_first_and_counted_in_the_final_fit(tmp_path, name, param, seed):
    rig, doc = _rig(tmp_path, seed, (name,))
    truth = rig.effects[name]["params"][param]
    assert [f["effect"] for f in doc["findings"]] == [name], doc["findings"]
    f = doc["findings"][0]
    assert f["channel"] == "tip_pos" and f["params"][param]["value"] == pytest.approx(truth, rel=0.05)
    assert f["improvement"] >= 2.0 and doc["unexplained"] == []
    # the lag is in the channel's final model: its held-out RMSE is the improvement's and at the noise floor
    tip = doc["channels"]["tip_pos"]
    assert tip["rmse_model"] == pytest.approx(f["rmse_after"]) and tip["rmse_model"] < 1.2 * TIP_NOISE_M


@pytest.mark.parametrize("pair, seed", [(("first_order_lag", "coulomb_friction"), 3),
                                        (("transport_delay", "backlash"), 4)])
def test_a_lag_beside_another_effect_both_named(tmp_path, pair, seed):
    rig, doc = _rig(tmp_path, seed, pair)
    named = [f["effect"] for f in doc["findings"]]
    assert set(named[:2]) == set(pair), doc["findings"]
    for name in pair:
        f = [g for g in doc["findings"] if g["effect"] == name][0]
        assert f["channel"] == rig.effects[name]["channel"] and f["improvement"] >= 2.0
        for p, true in rig.effects[name]["params"].items():
            if p in f["params"]:
                assert f["params"][p]["value"] == pytest.approx(true, rel=0.2), (name, p)


def _catheter(tmp_path) -> dict:
    """A tendon-driven catheter: tendon haul-in [mm] -> tip bending angle [deg], 1 kHz, 40 s, the tip following
    the tendon through a 45 ms first-order lag, 0.05 deg of angle noise; its diagnosis."""
    rng = np.random.default_rng(45)
    t = np.arange(40000) / 1000.0
    x = 2e-3 * np.sin(2 * np.pi * 0.3 * t) + 1e-3 * np.sin(2 * np.pi * 0.77 * t + 1.0) + \
        0.5e-3 * np.sin(2 * np.pi * 1.9 * t + 2.0)
    angle = np.rad2deg(15.0 * first_order_lag(t, x, 0.045))            # 15 rad of bend per m of tendon
    path = write_interchange(tmp_path / "catheter.csv", t,
                             {"motor_pos": x + rng.normal(0, 1e-6, t.size),
                              "tip_pos": np.deg2rad(angle + rng.normal(0, 0.05, t.size))},
                             {"motor_pos": "m", "tip_pos": "rad"}, {"source": "catheter"})
    return diagnose(read_interchange(path)).as_dict()


def test_a_catheter_whose_only_structure_is_a_45_ms_lag(tmp_path):
    doc = _catheter(tmp_path)
    assert [f["effect"] for f in doc["findings"]] == ["first_order_lag"], doc["findings"]
    f = doc["findings"][0]
    assert f["params"]["tau"]["value"] == pytest.approx(0.045, rel=0.05) and f["params"]["tau"]["unit"] == "s"
    assert doc["unexplained"] == []                                      # not an "unexplained delay"
    tip = doc["channels"]["tip_pos"]
    assert tip["rmse_model"] < 1.2 * np.deg2rad(0.05) and f["improvement"] >= 2.0


def test_a_late_tip_force_sensor_is_a_delay_not_friction(tmp_path):
    # the bench's tip force sensor reading late on a spring rig: the delay of the spring law's link, taken
    # out of the tip force before the sheath's link reads it (no friction named for it)
    rig, doc = _rig(tmp_path, 12, ("sensor_delay",), SPRING_NO_TIP, "spring", drive=False)
    assert [(f["effect"], f["channel"]) for f in doc["findings"]] == [("transport_delay", "tip_force")], doc
    delay = doc["findings"][0]["params"]["delay"]["value"]
    assert delay == pytest.approx(rig.effects["sensor_delay"]["params"]["delay"], rel=0.05)
    assert doc["unexplained"] == []


def test_an_effect_free_recording_names_no_lag(tmp_path):
    # (the sheath's link is the baseline's: whether it names nothing is tests/diagnosis/test_generated.py's)
    _, doc = _rig(tmp_path, 5, ("none",))
    assert not [f for f in doc["findings"] if f["channel"] == "tip_pos" or f["effect"].endswith(("delay", "lag"))]
    assert doc["channels"]["tip_pos"]["rmse_model"] < 1.2 * TIP_NOISE_M


if __name__ == "__main__":   # python -m tests.diagnosis.test_lag_named: the held-out figures of each case
    import tempfile
    from pathlib import Path

    tmp = Path(tempfile.mkdtemp())
    cases = [(n, _rig(tmp, s, (n,))) for n, s in (("transport_delay", 1), ("first_order_lag", 2))]
    cases += [("+".join(p), _rig(tmp, s, p)) for p, s in ((("first_order_lag", "coulomb_friction"), 3),
                                                          (("transport_delay", "backlash"), 4))]
    cases += [("late tip-force sensor", _rig(tmp, 12, ("sensor_delay",), SPRING_NO_TIP, "spring", drive=False)),
              ("effect-free", _rig(tmp, 5, ("none",))), ("catheter", (None, _catheter(tmp)))]
    for label, (rig, doc) in cases:
        print(f"{label}: truth {rig.effects if rig else {'first_order_lag': {'tau': 0.045}}}")
        for f in doc["findings"]:
            ps = ", ".join(f"{k} = {v['value']:.4g}" for k, v in f["params"].items() if not k.endswith("_input"))
            ch = doc["channels"][f["channel"]]
            print(f"  {f['effect']} on {f['channel']} ({ps}): held-out RMSE {f['rmse_before']:.3g} -> "
                  f"{f['rmse_after']:.3g}, x{f['improvement']:.2f}; channel final {ch['rmse_model']:.3g}")
        print(f"  unexplained: {[u['correlate'] for u in doc['unexplained']]}")
