"""`teleop geometry`: validate a geometry file and print the cable lengths, bending angles and tensions at a pose."""

from __future__ import annotations

import numpy as np

from teleop.apps.argtypes import finite_float, input_file
from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry, load_geometry
from teleop.core.kinematics import bending_angles, pose2cables, pose2lengths_checked, structure_matrix
from teleop.core.tension import wrench2tensions
from teleop.io.outputs import write_json


def register(subparsers) -> None:
    p = subparsers.add_parser("geometry", help="check a geometry TOML and show kinematics at a pose")
    p.add_argument("--geometry", type=input_file, metavar="TOML", help="geometry file (default: the seed robot)")
    p.add_argument("--pose-mm-deg", nargs=6, type=finite_float, default=[0, 0, 0, 0, 0, 0],
                   metavar=("X", "Y", "Z", "ALPHA", "BETA", "GAMMA"), help="pose in mm and deg (Z-Y-X Euler)")
    p.add_argument("--json", metavar="PATH", help="write the result as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    geom = load_geometry(args.geometry) if args.geometry else default_geometry()
    v = np.asarray(args.pose_mm_deg, dtype=float)
    pose = np.r_[v[:3] * 1e-3, np.deg2rad(v[3:])]
    try:
        lengths = pose2lengths_checked(pose, geom)
    except InputError as exc:
        raise InputError(f"--pose-mm-deg {' '.join(f'{x:g}' for x in v)}: {exc}") from None
    theta = bending_angles(pose2cables(pose, geom), geom)
    t = wrench2tensions(np.zeros(6), structure_matrix(pose, geom), geom.t_min, geom.t_max)
    result = {"pose_mm_deg": v.tolist(), "lengths_mm": (lengths * 1e3).tolist(),
              "bending_deg": np.rad2deg(theta).tolist(), "pretension_N": t.tolist()}
    print("cable  length[mm]  bend[deg]  pretension[N]")
    for i in range(6):
        print(f"{i + 1:>5}  {lengths[i] * 1e3:10.3f}  {np.rad2deg(theta[i]):9.2f}  {t[i]:13.3f}")
    if args.json:
        write_json(args.json, result)
    return 0
