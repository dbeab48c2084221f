"""`teleop session --sim-clock`: the same URLs and seeds record the same session whatever the machine's load
(a paced session's tick times follow the scheduler, so its stylus samples and commands differ run to run);
the flag's preconditions are one line and exit 2."""

import pytest

from teleop.apps.cli import main
from teleop.io.recording import TOPIC_ROBOT, read_session


def _rows(path):
    return [(m["seq"], tuple(m["commanded_lengths"]), tuple(m["x_t_fsr"]))
            for m in read_session(str(path)).messages(TOPIC_ROBOT)]


def test_two_sim_clock_sessions_record_the_same_robot_stream(tmp_path, capsys):
    runs = []
    for name in ("a", "b"):
        rec = tmp_path / f"{name}.mcap"
        assert main(["session", "--haptic", "sim://?script=pokes&depth_mm=10&period_s=0.5&seed=3",
                     "--robot", "sim://robot?seed=3", "--seconds", "1", "--robot-inline", "--sim-clock",
                     "--record", str(rec)]) == 0
        runs.append(_rows(rec))
    capsys.readouterr()
    assert len(runs[0]) >= 990 and runs[0] == runs[1]
    # the operator really moved the robot in that one simulated second
    first, last = runs[0][0][1], max(runs[0], key=lambda r: abs(r[1][0] - runs[0][0][1][0]))[1]
    assert abs(last[0] - first[0]) > 1e-4


@pytest.mark.parametrize("flags, match", [(["--sim-clock"], "--sim-clock needs --robot-inline"),
                                          (["--sim-clock", "--robot-inline", "--haptic", "touch://"],
                                           "needs a simulated stylus")])
def test_sim_clock_preconditions_are_one_line_exit_2(tmp_path, capsys, flags, match):
    rc = main(["session", "--seconds", "0.1", "--record", str(tmp_path / "s.mcap"), *flags])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and match in err
    assert not list(tmp_path.iterdir())
