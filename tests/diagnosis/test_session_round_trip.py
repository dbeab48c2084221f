"""The diagnosis handed back to the simulation, on a real recorded session (teleop bench session-diagnose): a
Coulomb friction switched on in the simulated robot beyond its sheath's capstan is named on the exported
cable, and the model saved from the diagnosis, loaded back into the simulated robot, replays the session's
commands with a residual several times smaller than the plain robot's."""

import pytest

from teleop.bench.session_diagnosis import bench_session_diagnosis, parse_effect
from teleop.errors import InputError


def test_coulomb_found_in_a_session_and_handed_back(tmp_path):
    # 20 s (ten pokes) on the simulated clock: the same session on any machine (paced, the CI's run named the
    # Coulomb friction a sensor hysteresis of the same size: motion and force reverse together in a poke).
    # Seeds 1-6 (--truth drive): Coulomb named first on 5, Fc 0.266-0.270 N; seed 5 a sensor hysteresis
    out = bench_session_diagnosis("coulomb_friction", {"Fc": 0.3}, seconds=20.0, seed=1, cable=1, work=tmp_path)
    assert out["found"] and out["found"][0]["effect"] == "coulomb_friction", out["found"]
    assert out["replay_rmse_N"]["as_recorded"] < 1e-9      # the replay is the recorded robot, reading by reading
    assert abs(out["recovered"]["Fc"] - 0.3) < 0.2 * 0.3
    assert out["shrink"] >= 2.0, out["replay_rmse_N"]


@pytest.mark.parametrize("text, match", [("coulomb_friction:Fk=1", "no parameter 'Fk'"),
                                         ("coulomb_friction:Fc=x", "must be a number"),
                                         ("backlash:width=0.001", "force-link effects"),
                                         ("warp_drive", "unknown effect")])
def test_bad_effect_flag_names_it(text, match):
    with pytest.raises(InputError, match=match):
        parse_effect(text)
