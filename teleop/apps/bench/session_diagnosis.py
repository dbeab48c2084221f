"""`teleop bench session-diagnose`: a recorded session on the simulated robot, diagnosed, and the identified
model handed back to the simulation.

    teleop bench session-diagnose --effect coulomb_friction:Fc=0.3 --seconds 20 --seed 1 --json F
    teleop bench session-diagnose --effect coulomb_friction:Fc=0.3 --effect viscous_friction:b=20 ...

1. Frictions the project's simulation does not have are switched on in the simulated robot: a link model
   whose baseline is the sheath's capstan and the EFFECTs (one, or a compound with --effect repeated) lie
   beyond it (`sim://robot?model=A`).
2. A `teleop session` on it is recorded on a simulated clock (`--sim-clock`: the same session on any machine;
   the simulated operator's pokes; the robot read every tick).
3. Cable --cable is exported (`teleop export --truth`: the simulator's tension at the FSR and the motor
   position its cable physics runs on, the simulation's sheath mu as a known baseline parameter), diagnosed
   (`teleop diagnose`), and its model saved (B). The same export is diagnosed again in the column subsets a
   lab records (COLUMN_SUBSETS: without the tip position, without the bend, without both).
4. The session's commanded lengths are replayed, reading by reading, through the simulated robot as it was
   (A: checks the replay reproduces the recording), without the effects, and with B. The residual (recorded
   tension at the FSR - replayed) of the plain robot against the one with B is the fit the handed-back
   model buys, in the session itself; the diagnosis's own held-out improvement is printed beside it.

JSON: {"effects": [{"effect", "params"}], "seconds", "seed", "cable", "found": [{"effect", "improvement",
"params"}] (motor_force findings, all columns), "recovered": {effect: {param: value}}, "elsewhere": [{"effect",
"channel", "improvement"}] (findings on other channels, not handed back), "subsets": [{"columns", "dropped",
"found": [effect names on motor_force], "named"}], "replay_rmse_N": {"as_recorded", "plain", "identified"},
"shrink" (plain / identified), "pass" (every switched-on effect named on motor_force, one of them first, in
every subset, and shrink >= 2)}.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from scenes.sim_robot import SimRobotParams
from teleop.apps.argtypes import add_geometry_option, geometry_of
from teleop.core.errors import InputError
from teleop.core.geometry import Geometry, load_geometry
from teleop.core.physics import get_effect
from teleop.core.physics.links import Link, LinkModel
from teleop.diagnosis.diagnose import diagnose
from teleop.io.model_io import load_model, save_model
from teleop.io.outputs import write_json
from teleop.io.recording import TOPIC_ROBOT, read_session
from teleop.io.recording_io import read_interchange
from teleop.loop.devices_by_url import open_device

SCRIPT = "sim://?script=pokes&depth_mm=10&period_s=2&seed={seed}"
# column subsets diagnosed besides the full export: name -> interchange channels dropped
COLUMN_SUBSETS = {"no tip position": ("tip_pos",), "no bend": ("bend_angle",),
                  "no tip position, no bend": ("tip_pos", "bend_angle")}


def register(subparsers) -> None:
    p = subparsers.add_parser("session-diagnose", help="a recorded simulated-robot session with a friction switched "
                                                      "on: diagnosed, and the model handed back to the simulation")
    p.add_argument("--effect", action="append", metavar="EFFECT:PARAM=VALUE[,...]",
                   help="a force-link effect switched on beyond the capstan (SI); repeat for a compound "
                        "(default coulomb_friction:Fc=0.3)")
    p.add_argument("--seconds", type=float, default=20.0, help="session length [s] (default 20)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--cable", type=int, default=1, help="cable exported and diagnosed, 1..6 (default 1)")
    p.add_argument("--json", metavar="F")
    add_geometry_option(p)
    p.add_argument("--out", metavar="DIR", help="keep the session, the exported CSV and both models in DIR "
                                                "(default: a temporary directory, removed)")
    p.set_defaults(func=run)


def parse_effect(text: str) -> tuple[str, dict]:
    """'coulomb_friction:Fc=0.3' -> ('coulomb_friction', {'Fc': 0.3}); InputError naming the flag otherwise."""
    name, _, rest = text.partition(":")
    try:
        eff = get_effect(name)
    except InputError as exc:  # the catalogue's message does not know the flag
        raise InputError(f"--effect {text}: {exc}") from None
    params = {s.name: s.default for s in eff.params}
    for item in filter(None, rest.split(",")):
        key, _, value = item.partition("=")
        if key not in params:
            raise InputError(f"--effect {text}: '{name}' has no parameter '{key}' (expected {', '.join(params)})")
        try:
            params[key] = float(value)
        except ValueError:
            raise InputError(f"--effect {text}: {key} must be a number, got {value!r}") from None
    if eff.link != "force":
        raise InputError(f"--effect {text}: the simulated robot takes force-link effects (got a {eff.link} effect)")
    return name, params


def _teleop(*args: str) -> None:
    cmd = [sys.executable, "-m", "teleop.apps.cli", *args]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(args[:2])} failed ({res.returncode}): {res.stderr.strip()[-500:]}")


def _recorded(path: Path, cable: int) -> tuple[np.ndarray, np.ndarray]:
    """(commanded lengths (n, 6) [m], simulator's FSR-side tension of `cable` (n,) [N]), one row per reading."""
    L, T, seen = [], [], set()
    for m in read_session(path).messages(TOPIC_ROBOT):
        if m["seq"] in seen:
            continue
        seen.add(m["seq"])
        L.append(m["commanded_lengths"])
        T.append(m["x_t_fsr"][cable - 1])
    return np.asarray(L, dtype=float), np.asarray(T, dtype=float)


def replay(url: str, lengths: np.ndarray, cable: int, geometry: Geometry | None = None) -> np.ndarray:
    """FSR-side tension of `cable` (n,) [N] of the robot at `url` (on `geometry`, None: the seed robot's)
    commanded `lengths` (n, 6), read once each."""
    out = np.empty(len(lengths))
    with open_device(url, geometry=geometry) as robot:
        for k, L in enumerate(lengths):
            robot.command_lengths(L)
            out[k] = robot.read().extras["t_fsr"][cable - 1]
    return out


def bench_session_diagnosis(effects: list, seconds: float, seed: int, cable: int, work: Path,
                            subsets: bool = True, geometry_file: str | None = None) -> dict:
    """The round trip for `effects` [(name, params)] switched on together (see the module docstring), on the
    robot of `geometry_file` (None: the seed robot)."""
    geometry = load_geometry(geometry_file) if geometry_file else None
    on_geometry = ("--geometry", str(geometry_file)) if geometry_file else ()
    # the robot's own capstan, as the model's baseline (baseline effects are not added again: the robot has it)
    sheath = (SimRobotParams(geometry=geometry) if geometry is not None else SimRobotParams()).sheath
    force = Link("force", "motor_force", "tip_force", "motor_pos")
    capstan = ("capstan_friction", {"mu": float(sheath.mu), "theta": float(sheath.theta0), "k": float(sheath.stick_k)})
    names = [name for name, _ in effects]
    model_a = work / "switched_on.json"
    save_model(model_a, [LinkModel(force, 1.0, 0.0, 1.0, 1.0, (capstan, *((n, dict(p)) for n, p in effects)), 1)],
               "teleop bench session-diagnose")
    robot = f"sim://robot?seed={seed}"
    mcap, csv, model_b = work / "session.mcap", work / f"cable{cable}.csv", work / "identified.json"
    print(f"session-diagnose: recording a {seconds:g} s session with {' + '.join(names)} switched on ...",
          flush=True)
    _teleop("session", "--haptic", SCRIPT.format(seed=seed), "--robot", f"{robot}&model={model_a}",
            "--seconds", str(seconds), "--robot-inline", "--sim-clock", "--record", str(mcap), *on_geometry)
    _teleop("export", str(mcap), "--csv", str(csv), "--cable", str(cable), "--truth")
    print("session-diagnose: diagnosing the exported cable ...", flush=True)
    rec = read_interchange(csv)
    diag = diagnose(rec)
    doc = diag.as_dict()
    # the simulated robot takes force-link findings (a per-cable play or stretch would give six lengths no
    # pose has): the force link's model is handed back; findings on other channels are reported
    save_model(model_b, [res.final.model for res in diag.links if res.data.link.kind == "force"], str(csv))
    elsewhere = [{"effect": f["effect"], "channel": f["channel"], "improvement": f["improvement"]}
                 for f in doc["findings"] if f["channel"] != "motor_force"]
    found = [{"effect": f["effect"], "improvement": f["improvement"],
              "params": {k: v["value"] for k, v in f["params"].items()}} for f in doc["findings"]
             if f["channel"] == "motor_force"]
    identified = load_model(model_b).links.get("force")
    fitted = dict(identified.effects[identified.base:]) if identified is not None else {}
    recovered = {name: fitted[name] for name in names if name in fitted}
    per_subset = [_subset("all columns", (), [f["effect"] for f in found], names)]
    for label, dropped in (COLUMN_SUBSETS.items() if subsets else ()):
        print(f"session-diagnose: diagnosing it without {', '.join(dropped)} ...", flush=True)
        sub = dataclasses.replace(rec, channels={k: v for k, v in rec.channels.items() if k not in dropped},
                                  units={k: v for k, v in rec.units.items() if k not in dropped})
        d = diagnose(sub).as_dict()
        per_subset.append(_subset(label, dropped, [f["effect"] for f in d["findings"]
                                                   if f["channel"] == "motor_force"], names))
    print("session-diagnose: replaying the session's commands through the simulated robot ...", flush=True)
    lengths, recorded = _recorded(mcap, cable)
    rmse = {}
    for name, url in (("as_recorded", f"{robot}&model={model_a}"), ("plain", robot),
                      ("identified", f"{robot}&model={model_b}")):
        rmse[name] = float(np.sqrt(np.mean((recorded - replay(url, lengths, cable, geometry)) ** 2)))
    shrink = rmse["plain"] / max(rmse["identified"], 1e-12)
    return {"effects": [{"effect": n, "params": dict(p)} for n, p in effects], "seconds": seconds, "seed": seed,
            "cable": cable, "found": found, "recovered": recovered, "elsewhere": elsewhere, "subsets": per_subset,
            "replay_rmse_N": rmse, "shrink": shrink,
            "pass": all(s["named"] for s in per_subset) and shrink >= 2.0,
            **({"geometry_file": str(geometry_file)} if geometry_file else {})}


def _subset(label: str, dropped: tuple, found: list, switched_on: list) -> dict:
    """One column subset's verdict: every switched-on effect named, one of them first."""
    named = bool(found) and found[0] in switched_on and set(switched_on) <= set(found)
    return {"columns": label, "dropped": list(dropped), "found": found, "named": named}


def run(args) -> int:
    if not 1 <= args.cable <= 6:
        raise InputError(f"--cable must be 1..6, got {args.cable}")
    if not 2.0 <= args.seconds <= 600.0:
        raise InputError(f"--seconds must be in [2, 600], got {args.seconds}")
    effects = [parse_effect(text) for text in (args.effect or ["coulomb_friction:Fc=0.3"])]
    if len({name for name, _ in effects}) != len(effects):
        raise InputError("--effect: each effect at most once")
    geometry_of(args)  # a bad --geometry: one line before the session
    if args.out:
        work = Path(args.out).absolute()  # the child commands' arguments never start with '-'
        if work.exists() and not work.is_dir():
            raise InputError(f"--out {args.out}: exists and is not a directory")
        work.mkdir(parents=True, exist_ok=True)
        out = bench_session_diagnosis(effects, args.seconds, args.seed, args.cable, work, geometry_file=args.geometry)
    else:
        with tempfile.TemporaryDirectory(prefix="session-diagnose-") as tmp:
            out = bench_session_diagnosis(effects, args.seconds, args.seed, args.cable, Path(tmp),
                                          geometry_file=args.geometry)
    found = ", ".join(f"{f['effect']} x{f['improvement']:.2f}" for f in out["found"]) or "none"
    r = out["replay_rmse_N"]
    switched = " + ".join(f"{e['effect']} {e['params']}" for e in out["effects"])
    print(f"switched on: {switched}; found on motor_force: {found}; recovered {out['recovered']}")
    for s in out["subsets"][1:]:
        print(f"  {s['columns']}: {', '.join(s['found']) or 'none'}" + ("" if s["named"] else "  (MISSED)"))
    for f in out["elsewhere"]:
        print(f"also found (not handed back: the robot takes force-link effects): {f['effect']} on {f['channel']} "
              f"x{f['improvement']:.2f}")
    print(f"replay residual [N]: as recorded {r['as_recorded']:.4f}, plain robot {r['plain']:.4f}, with the "
          f"identified model {r['identified']:.4f}: x{out['shrink']:.2f} ({'PASS' if out['pass'] else 'FAIL'})")
    if args.json:
        write_json(args.json, out)
    return 0
