"""The simulated robot takes an identified link model back (`sim://robot?model=FILE`, the file of
`teleop diagnose --save-model`): the model's force-link findings act on every cable's tension at the FSR
through the same physics Steps the diagnosis fitted; its baseline effects are not added twice; position
effects, which would give six lengths no pose has, are refused with one line."""

import numpy as np
import pytest

from teleop.loop.devices_by_url import open_device
from teleop.core.physics.links import Link, LinkModel
from teleop.io.model_io import load_model, save_model
from teleop.core.errors import InputError
from teleop.core.physics import Signals, get_effect

FORCE = Link("force", "motor_force", "tip_force", "motor_pos")


def _readings(url, lengths):
    out = []
    with open_device(url) as robot:
        for L in lengths:
            robot.command_lengths(L)
            out.append(robot.read())
    return out


def test_force_findings_act_on_the_fsr_tension(tmp_path):
    path = tmp_path / "m.json"
    capstan = ("capstan_friction", {"mu": 0.05, "theta": 2.4, "k": 2e4})    # the baseline: not added again
    coulomb = ("coulomb_friction", {"Fc": 0.3})
    save_model(path, [LinkModel(FORCE, 1.0, 0.0, 1.0, 1.0, (capstan, coulomb), 1)], "test")
    assert load_model(path).links["force"].base == 1
    from scenes.sim_robot import home_pose
    from teleop.core.geometry import default_geometry
    from teleop.core.kinematics import poses2lengths
    geom = default_geometry()
    p0 = home_pose()
    poses = np.repeat(p0[None, :], 60, axis=0)
    poses[:, 2] += 1e-3 * np.sin(np.linspace(0, 2 * np.pi, 60))        # up and down: both directions
    lengths = poses2lengths(poses, geom)
    plain = _readings("sim://robot?seed=2", lengths)
    added = _readings(f"sim://robot?seed=2&model={path}", lengths)
    x = -lengths
    for k in range(2, 60):
        t_plain, t_added = plain[k].extras["t_fsr"], added[k].extras["t_fsr"]
        v = np.sign(x[k] - x[k - 1])
        assert np.allclose(t_added - t_plain, 0.3 * v, atol=1e-9)


def test_position_effects_are_refused(tmp_path):
    path = tmp_path / "p.json"
    pos = Link("position", "tip_pos", "motor_pos", "motor_pos")
    save_model(path, [LinkModel(pos, 1.0, 0.0, 1.0, 1.0, (("backlash", {"width": 1e-4}),), 0)], "test")
    with pytest.raises(InputError, match="position-link effects"):
        with open_device(f"sim://robot?model={path}"):
            pass
