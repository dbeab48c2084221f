"""`teleop palpate`: the palpation tests of seed 000 §5.1 on the simulated robot (pybullet pads)."""

from __future__ import annotations

import dataclasses
import sys

from scenes.sim_robot import PLANTS
from teleop.apps.argtypes import add_geometry_option, geometry_of, input_file
from teleop.apps.protocols import palpation
from teleop.apps.protocols.palpation_sensors import sensor_calibration
from teleop.core.errors import InputError
from teleop.core.geometry import geometry_dict
from teleop.io.outputs import save_figure, write_json


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "palpate", help="palpation tests on the simulated robot: stiffness (Table 1), z / xy (Fig 16), scan (Fig 17)",
        description="Run a palpation test of seed 000 on the simulated CDPR and pybullet pads; print a table, "
                    "write the JSON (--json) and a figure (--plot).")
    p.add_argument("--test", required=True, choices=("stiffness", "z", "xy", "scan"), help="which test")
    p.add_argument("--speed-profile", default="uniform", choices=("uniform", "variable"),
                   help="uniform 0.5 mm/s pokes, or variable speed with reversals (default uniform)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sensor noise and the variable profile")
    p.add_argument("--plant", default="matched", choices=PLANTS,
                   help="matched: the robot's physics is the estimators' model; rich: with effects none of them "
                        "models (sheath float, Stribeck, Dahl, guide pulley, FSR creep; scenes/rich_plant.py), "
                        "drawn per cable from --seed; distributed: the distributed tendon-sheath cable "
                        "(scenes/tendon_sheath.py) in place of the lumped sheath (default matched)")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --plant distributed: the cable's parameters, a [tendon_sheath] table "
                        "(docs/formats.md; default its built-in values)")
    p.add_argument("--repeats", type=int, default=None, help="z test repetitions (default 5, as the seed)")
    p.add_argument("--limit", type=int, default=None, help="keep only the first N pokes of each run (quick look)")
    p.add_argument("--sensor", default="fsr", choices=("fsr", "fbg", "one"),
                   help="the robot's tension sensors: fsr (the FSR array, default), fbg (seed 001's distal FBG "
                        "on every cable, temperature compensated) or one (the FSR array plus one cable's FBG, "
                        "seed 001's sensor-model approach for the others)")
    p.add_argument("--calibration", type=input_file, default=None, metavar="TOML",
                   help="with --sensor fbg|one: a `teleop calibrate fbg` file (the FBGs' constants) or, with "
                        "--sensor one, a `teleop calibrate one-sensor` file (Kp, Kr: not identified on the run)")
    add_geometry_option(p)
    p.add_argument("--json", default=None, help="write the results as JSON here")
    p.add_argument("--plot", default=None, help="write a PNG figure here")
    p.set_defaults(func=run)


def run(args) -> int:
    geometry = geometry_of(args)  # a bad file is one line before the run
    params = dataclasses.replace(palpation.PalpationParams(), sensor=args.sensor, calibration=args.calibration)
    if args.calibration is not None:  # a file that does not fit the sensor is refused before the run
        sensor_calibration(args.calibration, args.sensor)
    if args.repeats is not None:
        if args.repeats < 1:
            raise InputError(f"--repeats must be >= 1, got {args.repeats}")
        params = dataclasses.replace(params, repeats_z=args.repeats)
    if args.limit is not None and args.limit < 1:
        raise InputError(f"--limit must be >= 1, got {args.limit}")
    res = palpation.run_test(args.test, args.speed_profile, args.seed, params, limit=args.limit, progress=True,
                   plant=args.plant, cable_params=args.cable_params, geometry=geometry)
    print(res.table())
    if args.json:  # the geometry only when given: the seed robot's JSON is what it was
        extra = {"geometry_file": args.geometry, "geometry": geometry_dict(geometry)} if args.geometry else {}
        write_json(args.json, {**res.to_json(), **extra})
    if args.plot:
        save_figure(res.plot(), args.plot)
    sys.stdout.flush()
    return 0
