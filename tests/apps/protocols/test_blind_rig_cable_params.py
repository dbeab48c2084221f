"""The blind-test rig builds its simulated robot with the distributed cable's --cable-params, as palpate does."""

import pytest

from scenes.pads import blind_test_pad
from scenes.tendon_sheath import TendonSheathParams
from teleop.apps.cli import main
from teleop.apps.protocols.blind.rig import RigOptions, Station, rig_dict
from teleop.core.errors import InputError


@pytest.fixture
def toml(tmp_path):
    path = tmp_path / "cable.toml"
    path.write_text("[tendon_sheath]\nn_elements = 24\nmu_c = 0.05\nmu_s = 0.06\n")
    return path


def test_each_station_reads_the_cable_params(toml):
    station = Station(blind_test_pad(), RigOptions(plant="distributed", cable_params=str(toml)), (0, 1))
    cable = station.robot.params.cable
    assert cable.n_elements == 24 and cable.mu_c == 0.05 and cable.mu_s == 0.06
    default = Station(blind_test_pad(), RigOptions(plant="distributed"), (0, 1)).robot.params.cable
    assert default == TendonSheathParams() and default != cable
    # listed in the rig's dict (results' config, campaign identity) only when given
    assert rig_dict(RigOptions(plant="distributed", cable_params=str(toml)))["cable_params"] == str(toml)
    assert "cable_params" not in rig_dict(RigOptions(plant="distributed"))


def test_cable_params_need_the_distributed_plant(toml):
    with pytest.raises(InputError, match="cable_params"):
        RigOptions(plant="matched", cable_params=str(toml))


@pytest.mark.parametrize("argv, words", [
    (["--plant", "matched", "--cable-params", "{toml}"], "--cable-params"),
    (["--plant", "distributed", "--cable-params", "{bad}"], "unknown key"),
])
def test_cli_refuses_bad_cable_params_in_one_line(tmp_path, toml, capsys, argv, words):
    bad = tmp_path / "bad.toml"
    bad.write_text("[tendon_sheath]\nEA = 7000\n")
    argv = [a.format(toml=toml, bad=bad) for a in argv]
    assert main(["blind-test", "--participants", "1", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1
