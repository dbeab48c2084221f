"""The simulated robot with the distributed tendon-sheath cable (`sim://robot?plant=distributed`,
`--plant distributed`): it runs a session, its sensors read the element tensions where each sits, the
per-reading and batch paths agree, and every command that takes --plant takes it."""

import json
import subprocess
import sys

import numpy as np
import pytest

from scenes.pads import blind_test_pad
from scenes.rich_plant import RichPlantParams
from scenes.sim_robot import DistributedCables, SimRobot, SimRobotParams, with_named_plant
from scenes.tendon_sheath import TendonSheathParams, tension_at_b
from teleop.apps.bench.feedforward import bench_feedforward
from teleop.apps.bench.sim import bench_sim
from teleop.apps.campaign.blind import make_point
from teleop.apps.protocols.blind.rig import RigOptions, Station, rig_dict
from teleop.apps.cli import build_parser, main
from teleop.core.errors import InputError
from teleop.core.kinematics import poses2lengths
from teleop.loop.devices_by_url import open_device


def _press(n=1200, depth=8e-3):
    """(n, 6) poses: the end effector down `depth` [m] along z and back (the pad's contact on the way)."""
    z = np.concatenate([np.linspace(0.0, depth, n // 2), np.linspace(depth, 0.0, n - n // 2)])
    q = np.zeros((n, 6))
    q[:, 2] = z
    return q


def _read_all(robot, L):
    rows = []
    for row in L:
        robot.command_lengths(row)
        r = robot.read()
        rows.append((r.extras["t_fsr"].copy(), r.extras["t_tip"].copy(), r.extras["t_motor"].copy(),
                     r.fsr_counts.copy()))
    return [np.array(a) for a in zip(*rows)]


def test_a_session_with_the_distributed_cable_enables_and_pokes():
    out = bench_sim(0.5, seed=2, batch=False, stages=False, plant="distributed")
    tr = out["trajectory"]
    assert out["plant"] == "distributed" and out["ticks"] == 500
    assert tr["final_state"] == "ENABLED" and tr["fault_reason"] == "" and tr["enabled_s"] > 0.4
    assert out["realtime_factor"] > 0


def test_a_frictionless_sheath_reads_the_platform_tension_at_the_fsr():
    cable = TendonSheathParams(mu_c=0.0, mu_s=0.0)
    with SimRobot(params=SimRobotParams(cable=cable), seed=1) as robot:
        L = poses2lengths(_press(), robot.geom)
        t_fsr, t_tip, t_motor, _ = _read_all(robot, L)
    assert np.ptp(t_tip) > 0.5                      # the pose and the contact move the tensions
    # no friction: the cable is one tension, but for its mass where the motor's speed jumps (start, reversal)
    steady = np.ones(len(L), dtype=bool)
    steady[:5] = steady[598:605] = False
    assert np.abs(t_fsr - t_tip)[steady].max() < 1e-3 and np.abs(t_motor - t_tip)[steady].max() < 1e-3
    assert np.abs(t_fsr - t_tip).max() < 2e-2


def test_friction_puts_the_motor_side_above_the_tip_side_while_hauling_in():
    with SimRobot(params=SimRobotParams(cable=TendonSheathParams()), seed=1) as robot:
        L = poses2lengths(_press(), robot.geom)
        t_fsr, t_tip, t_motor, _ = _read_all(robot, L)
        # the FSR reads the tension at B, between its node's two elements
        assert np.array_equal(tension_at_b(robot._cables.sheath.tensions, robot.params.cable), t_fsr[-1])
        j = robot._cables.j_fsr
        T = robot._cables.sheath.tensions
        assert np.all((T[:, j] - t_fsr[-1]) * (T[:, j - 1] - t_fsr[-1]) < 0)
    v = np.gradient(-L, axis=0)                     # haul-in speed of each cable
    hauling, paying = v > 1e-7, v < -1e-7
    settled = np.zeros(len(L), dtype=bool)
    settled[200:550] = settled[800:1150] = True     # away from the start and the reversal
    assert (hauling & settled[:, None]).sum() > 100 and (paying & settled[:, None]).sum() > 100
    assert np.all((t_fsr > t_tip)[hauling & settled[:, None]])
    assert np.all((t_motor > t_fsr)[hauling & settled[:, None]])
    assert np.all((t_fsr < t_tip)[paying & settled[:, None]])


@pytest.mark.parametrize("sensor", ["fsr", "fbg"])
def test_the_batch_path_reads_what_the_readings_read(sensor):
    params = SimRobotParams(cable=TendonSheathParams(), sensor=sensor)
    with SimRobot(params=params, seed=4) as robot:
        L = poses2lengths(_press(600), robot.geom)
        t_fsr, t_tip, _, counts = _read_all(robot, L)
    with SimRobot(params=params, seed=4) as robot:
        trace = robot.run(L)
    assert np.allclose(trace.t_fsr, t_fsr, atol=1e-9) and np.allclose(trace.t_tip, t_tip, atol=1e-9)
    assert np.array_equal(trace.counts, counts)


def test_the_fbg_reads_the_element_before_the_sheath_end():
    cables = DistributedCables(TendonSheathParams(), 6, 2.85, 1e-3)
    assert cables.j_fsr == 16 and cables.j_fbg == 19  # B at 0.80 m; 0.97 m of a 1 m sheath in 20 elements


def test_url_options_and_their_errors(tmp_path):
    toml = tmp_path / "cable.toml"
    toml.write_text("[tendon_sheath]\nn_elements = 24\nmu_c = 0.05\nmu_s = 0.06\n")
    robot = open_device(f"sim://robot?plant=distributed&cable_params={toml}")
    assert robot.params.cable.n_elements == 24 and robot.params.cable.mu_c == 0.05
    assert open_device("sim://robot?plant=distributed").params.cable == TendonSheathParams()
    assert open_device("sim://robot?plant=matched").params.cable is None
    with pytest.raises(InputError, match="plant=distributed"):
        open_device("sim://robot?cable=distributed")
    with pytest.raises(InputError, match="cable_params"):
        open_device(f"sim://robot?plant=rich&cable_params={toml}")
    bad = tmp_path / "bad.toml"
    bad.write_text("[tendon_sheath]\nEA = 7000\n")
    with pytest.raises(InputError, match="unknown key"):
        open_device(f"sim://robot?plant=distributed&cable_params={bad}")
    with pytest.raises(InputError, match="two plants"):
        SimRobotParams(plant=RichPlantParams(), cable=TendonSheathParams())
    assert with_named_plant(SimRobotParams(), "distributed", 0).cable == TendonSheathParams()


@pytest.mark.parametrize("argv", [
    ["palpate", "--test", "z", "--plant", "distributed"],
    ["bench", "sim", "--plant", "distributed"],
    ["bench", "cable", "--experiment", "fig9", "--plant", "distributed"],
    ["blind-test", "--plant", "distributed"],
    ["bench", "blind-jnd", "--plant", "distributed"],
    ["bench", "feedforward", "--plant", "distributed"],
])
def test_plant_distributed_is_accepted(argv):
    args = build_parser().parse_args(argv)
    assert args.plant == "distributed"
    with pytest.raises(SystemExit):
        build_parser().parse_args([a if a != "distributed" else "lumpy" for a in argv])


def test_feedforward_sessions_run_on_the_distributed_plant():
    out, runs = bench_feedforward(seconds=1.0, settle=0.5, plant="distributed")
    assert out["plant"] == "distributed"
    assert all(s["final_state"] == "ENABLED" and s["readings"] > 0 for s in out["sessions"].values())


def test_the_blind_rig_and_campaign_take_the_plant():
    pad = blind_test_pad()
    station = Station(pad, RigOptions(plant="distributed"), seed=(0, 1))
    assert station.robot.params.cable == TendonSheathParams()
    assert Station(pad, RigOptions(), seed=(0, 1)).robot.params.cable is None
    assert "plant" not in rig_dict(RigOptions()) and rig_dict(RigOptions(plant="rich"))["plant"] == "rich"
    point = make_point({}, {"plant": "distributed"}, {}, "campaign")
    assert point.rig["plant"] == "distributed" and "plant" not in make_point({}, {}, {}, "campaign").rig
    with pytest.raises(InputError, match="plant"):
        RigOptions(plant="lumpy")


def test_bench_cable_fig9_with_the_distributed_plant_keeps_its_keys(tmp_path):
    path = tmp_path / "c.json"
    assert main(["bench", "cable", "--experiment", "fig9", "--plant", "distributed", "--json", str(path)]) == 0
    out = json.loads(path.read_text())
    assert out["plant"] == "distributed"
    for deg in ("0", "30"):
        c = out["cases"][deg]
        # friction on the way to each point: more before the motor than before B (the FSR's own lag may hide B's)
        assert c["proximal_change_N"] > c["tension_B_change_N"] > 0.1
        assert "distal_change_N" in c and "seed" in c


def test_warm_up_compiles_the_distributed_cable():
    code = """
import json
from teleop.loop.warm import kernels, warm_up
from teleop.apps.bench.sim import bench_sim
warm_up()
before = {k.__name__: len(k.signatures) for k in kernels()}
bench_sim(seconds=0.1, batch=False, stages=False, plant="distributed")
after = {k.__name__: len(k.signatures) for k in kernels()}
new = {k: after[k] - before[k] for k in after if after[k] != before[k]}
bench_sim(seconds=0.1, batch=True, stages=False, plant="distributed")  # the batch path's cable: the same kernels
cable = {k.__name__: len(k.signatures) for k in kernels() if k.__module__ == "scenes.tendon_sheath_kernels"}
new.update({k: v - after[k] for k, v in cable.items() if v != after[k]})
print(json.dumps(new))
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) == {}
