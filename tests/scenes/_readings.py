"""The simulated robot read row by row and run in one batch on the same lengths (the two paths must agree)."""

from __future__ import annotations

import numpy as np

from scenes.sim_robot import SimRobot, SimRobotParams


def read_then_run(params: SimRobotParams, seed: int, lengths_of) -> tuple[list, object]:
    """Readings of each row of `lengths_of(geom)` (m, 6) [m] from one robot, then `run` of the same lengths on a
    fresh robot of the same params and seed: (the m readings' (fsr_counts, extras) copies, the SimTrace)."""
    rows = []
    with SimRobot(params=params, seed=seed) as robot:
        L = lengths_of(robot.geom)
        for row in L:
            robot.command_lengths(row)
            r = robot.read()
            rows.append((r.fsr_counts.copy(), {k: np.copy(v) for k, v in r.extras.items()}))
    with SimRobot(params=params, seed=seed) as robot:
        trace = robot.run(L)
    return rows, trace
