"""`teleop blind-test`: the blind stiffness-ranking study of seed 000 §5.2 (Table 3).

Simulated participants (default: 10 of them) poke the four-area pad through the whole simulated chain:
stylus -> mapping -> kinematics -> simulated CDPR and pybullet pads -> estimation -> rendering -> stylus.
`--operator human` guides a coordinator through the same protocol for real participants, saving every
answer so an interrupted study resumes where it stopped.
"""

from __future__ import annotations

import socket
import sys
from dataclasses import asdict

import numpy as np

from scenes.pads import blind_area_centres
from scenes.sim_robot import PLANTS
from scenes.tendon_sheath import TendonSheathParams
from teleop.apps.argtypes import (add_geometry_option, geometry_of, input_file, jnd_fraction, positive_float,
                                  positive_int)
from teleop.apps.commands.session import add_live_arguments
from teleop.apps.protocols.blind.human import Coordinator, run_human_study
from teleop.apps.protocols.blind.participants import RATING_RULES, ParticipantParams
from teleop.apps.protocols.blind.probe import PressAborted
from teleop.apps.protocols.blind.rig import (BackgroundSession, RehearsalStation, RigOptions, SimRig, blind_areas,
                                             rig_dict, transparency)
from teleop.apps.protocols.blind.study import run_simulated_study
from teleop.core.errors import InputError
from teleop.io.outputs import write_json
from teleop.io.progress import progress
from teleop.loop.live.study import StudyLiveView
from teleop.loop.warm import warm_up

DEFAULT_STATE = "blind_test_state.json"


def add_rig_options(p) -> None:
    """Options shared with `teleop bench blind-jnd`: the chain the participants feel."""
    p.add_argument("--no-compensation", action="store_true",
                   help="ablation: render the raw FSR wrench (no friction compensation, no Kalman)")
    p.add_argument("--force-scale", type=float, default=None, metavar="G",
                   help="stylus force per newton at the tip (default: the rig's; a tiny value degrades the chain)")
    p.add_argument("--tip-stiffness", type=float, default=None, metavar="N_PER_M",
                   help="series stiffness of the simulated robot at its tip [N/m] (default: the sim robot's, 1e4)")
    p.add_argument("--kalman-bandwidth", type=float, default=None, metavar="HZ",
                   help="-3 dB bandwidth of the estimator's Kalman filter [Hz] (default: the rig's, 80 Hz)")
    p.add_argument("--robot-substeps", type=int, default=None, metavar="N",
                   help="physics steps of 1 ms per robot-link exchange (default 1: the link at 1 kHz)")
    p.add_argument("--depth-mm", type=positive_float, default=None, metavar="MM",
                   help="participants' mean stylus push depth [mm]")
    p.add_argument("--speed-mm-s", type=positive_float, default=None, metavar="MM_S",
                   help="participants' mean stylus push speed [mm/s]")
    p.add_argument("--sensor", default="fsr", choices=("fsr", "fbg", "one"),
                   help="the robot's tension sensors: fsr (the FSR array, default), fbg (seed 001's distal FBG on "
                        "every cable) or one (the FSR array plus one cable's FBG, seed 001's sensor-model approach)")
    p.add_argument("--plant", default="matched", choices=PLANTS,
                   help="the simulated robot's plant: matched (default), rich (effects no estimator models, drawn "
                        "per robot) or distributed (the distributed tendon-sheath cable, scenes/tendon_sheath.py)")
    p.add_argument("--cable-params", type=input_file, default=None, metavar="TOML",
                   help="with --plant distributed: the cable's [tendon_sheath] table (docs/formats.md)")
    p.add_argument("--press-force", type=float, default=None, metavar="N",
                   help="participants press until the stylus force reaches about N newtons, capped by the "
                        "depth (default 0.2 N; 0: push by depth only)")
    add_geometry_option(p)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "blind-test", help="blind stiffness ranking (seed 000 Table 3): simulated or real participants",
        description="Participants poke four pad areas (rigid PLA, Dragon Skin 30, Ecoflex 00-50, Ecoflex 00-20) "
                    "through the haptic stylus without seeing them and rank their hardness.")
    p.add_argument("--operator", choices=("sim", "human"), default="sim",
                   help="simulated participants (default) or real ones guided by prompts")
    p.add_argument("--participants", type=positive_int, default=10, metavar="N", help="number of participants")
    p.add_argument("--seed", type=int, default=0, help="seed of layouts, orders and participants (default 0)")
    p.add_argument("--rating", default="positions", choices=RATING_RULES,
                   help="how a simulated participant's ranking becomes ratings: positions (ends drawn 8-10 and 1-3, the "
                        "middle placed between them; default) or anchored (every rating read off a scale two training "
                        "pads anchor; docs/plant-distributed.md)")
    p.add_argument("--jnd", type=jnd_fraction, default=None, metavar="J",
                   help="participants' stiffness JND as a Weber fraction, e.g. 0.23 or 23%% "
                        "(default 0.23, Jones & Hunter 1990)")
    add_rig_options(p)
    p.add_argument("--haptic", default="sim://", metavar="URL",
                   help="stylus: sim:// (default); with --operator human also touch://, omega:// or none")
    p.add_argument("--robot", default="sim://robot", metavar="URL", help="robot (default sim://robot)")
    p.add_argument("--state", default=DEFAULT_STATE, metavar="FILE",
                   help=f"--operator human: answers saved here after every step (default {DEFAULT_STATE})")
    p.add_argument("--json", metavar="PATH", help="write the results as JSON")
    p.add_argument("--plot", metavar="PATH", help="write a PNG: ratings per area and rendered vs true stiffness")
    p.add_argument("--transparency", action="store_true",
                   help="instead of the study: press each area 3 times at 10, 20 and 30 mm/s and compare the "
                        "stiffness rendered on the stylus with the unfiltered estimate and the robot's "
                        "ground-truth contact force (what limits the rendered ratios)")

    add_live_arguments(p)  # --operator human: the experimenter's screen (trial, pad, force, answers)
    p.set_defaults(func=run)


def participant_params(args):
    kw = {}
    if args.jnd is not None:
        kw["jnd"] = args.jnd
    if args.depth_mm is not None:
        kw["depth"] = args.depth_mm * 1e-3
    if args.speed_mm_s is not None:
        kw["speed"] = args.speed_mm_s * 1e-3
    if getattr(args, "press_force", None) is not None:
        kw["force"] = None if args.press_force == 0 else args.press_force
    return ParticipantParams(**kw)


def rig_options(args):
    kw = {"compensation": not args.no_compensation}
    if args.force_scale is not None:
        kw["force_scale"] = args.force_scale
    if args.tip_stiffness is not None:
        kw["tip_stiffness"] = args.tip_stiffness
    if getattr(args, "kalman_bandwidth", None) is not None:
        kw["kalman_bandwidth"] = args.kalman_bandwidth
    if getattr(args, "robot_substeps", None) is not None:
        kw["robot_substeps"] = args.robot_substeps
    kw["sensor"] = getattr(args, "sensor", "fsr")
    kw["plant"] = getattr(args, "plant", "matched")
    cable_params = getattr(args, "cable_params", None)
    if cable_params is not None:
        if kw["plant"] != "distributed":
            raise InputError("--cable-params: the cable's parameters belong to --plant distributed")
        TendonSheathParams.from_toml(cable_params)  # a bad file or key is one line now, before any station reads it
        kw["cable_params"] = cable_params
    if getattr(args, "geometry", None):
        geometry_of(args)  # a bad file or key is one line now, before any station reads it
        kw["geometry"] = args.geometry
    return RigOptions(**kw)


def run(args) -> int:
    if args.live is not None and args.operator != "human":
        raise InputError("--live serves the experimenter's screen of --operator human (the simulated study runs "
                         "faster than real time; watch a session with `teleop session --live`)")
    if args.operator == "human":
        if args.rating != "positions":  # real participants give their own numbers (the seed's rule, checked)
            raise InputError(f"--rating {args.rating}: the rating rule is the simulated participants'; real ones "
                             f"rate by the seed's rule (--operator human)")
        return run_human(args)
    if getattr(args, "transparency", False):
        return run_transparency(args)
    return run_sim(args)


TRANSPARENCY_SPEEDS = (0.010, 0.020, 0.030)  # [m/s] stylus press speeds: the participants' 20 mm/s and around


def run_transparency(args) -> int:
    """Each area pressed at TRANSPARENCY_SPEEDS: median loading slopes [N/m] of the rendered force, the
    unfiltered estimate and the ground-truth contact force (x force scale) against the stylus displacement."""
    if args.haptic != "sim://" or args.robot != "sim://robot":
        raise InputError("blind-test --transparency runs on the simulated stylus and robot only")
    if args.plot:
        raise InputError(f"--plot {args.plot}: blind-test --transparency draws no figure (its table is printed; "
                         f"--json PATH saves it)")
    params = participant_params(args)
    if params.force is None:
        raise InputError("blind-test --transparency presses to a force: --press-force must be > 0")
    options = rig_options(args)
    rows = transparency(options, TRANSPARENCY_SPEEDS, repeats=3, force=params.force, depth=params.depth)
    labels = {a.name: a.label for a in blind_areas()}

    def med(values):
        v = [x for x in values if x is not None]
        return float(np.median(v)) if v else None

    def cell(v):
        return "        -" if v is None else f"{v:9.1f}"

    print("medians of 3 presses [N/m]; contact = force scale x ground-truth contact force, against the stylus")
    print(f"{'speed':>9}  {'area':16} {'rendered':>9} {'unfiltered':>10} {'contact':>9} {'transparent':>11}")
    for r in rows:
        print(f"{r['speed'] * 1e3:5.0f} mm/s  {labels[r['area']]:16} {cell(med(r['rendered']))} "
              f"{cell(med(r['unfiltered'])):>10} {cell(med(r['contact']))} {r['expected']:11.1f}")
    if args.json:
        write_json(args.json, {"speeds_m_per_s": list(TRANSPARENCY_SPEEDS), "press_force_N": params.force,
                               "rig": rig_dict(options), "rows": rows})
    return 0


def _progress(total: int, desc: str):
    """Participants done out of `total` on stderr, from a first line at once (tqdm's bar on a terminal)."""
    return progress(total, desc, unit="participants", start_line=True)


def run_sim(args) -> int:
    if args.haptic != "sim://" or args.robot != "sim://robot":
        raise InputError("blind-test --operator sim runs on the simulated stylus and robot only "
                         "(--haptic sim:// --robot sim://robot); use --operator human at a real rig")
    params = participant_params(args)
    options = rig_options(args)

    warm_up()  # compiled (saying so) or loaded before the progress starts: its ETA counts participants only
    with SimRig(options) as rig, _progress(args.participants, "blind test") as bar:
        try:
            result = run_simulated_study(rig, args.participants, args.seed, params, progress=bar.update,
                                         rating=args.rating)
        except PressAborted as exc:  # the options asked more of the simulated robot than its cables hold
            raise InputError(f"{exc}; a participant's push overloaded the simulated robot with these options "
                             f"(depth pushes into rigid need --press-force > 0)") from None
        config = {"operator": "sim", "participants": args.participants, "seed": args.seed,
                  "participant_params": _asdict(params), "rig": rig.describe(),
                  **({} if args.rating == "positions" else {"rating": args.rating})}  # former configs unchanged
        expected = rig.expected_stiffness()
    result = type(result)(areas=result.areas, records=result.records, config=config, expected=expected)
    print(result.table())
    print("\n(seed 000 Table 3 beside the simulated ratings; 'transparent chain': force scale x motion scale x the pad"
          " in series with the simulated robot's own stiffness, scenes.sim_robot tip_stiffness)")
    print(rig.attribution)
    _write_results(args, result)
    return 0


def _write_results(args, result) -> None:
    """Write --json and --plot and say where; without either, say what they would write."""
    if args.json:
        write_json(args.json, result.to_dict())
        print(f"wrote {args.json}")
    if args.plot:
        result.plot(args.plot)
        print(f"wrote {args.plot}")
    if not (args.json or args.plot):
        print("no file written: --json PATH saves the results (each participant's order and ratings, means, "
              "ranking rates), --plot PATH the figure")


def _asdict(obj) -> dict:
    return asdict(obj)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _study_live_view(args, areas, relay_port):
    """The experimenter's live screen (teleop.loop.live.study) on --live-host:--live."""
    try:
        return StudyLiveView(args.live_host, args.live, blind_area_centres(), {a.name: a.label for a in areas},
                             relay_port=relay_port).start()
    except OSError as exc:
        raise InputError(f"--live {args.live} --live-host {args.live_host}: {exc}") from None


def run_human(args) -> int:
    def write(text: str) -> None:
        sys.stdout.write(text)
        sys.stdout.flush()

    def read() -> str:
        line = sys.stdin.readline()
        if line and not sys.stdin.isatty():
            write(line if line.endswith("\n") else line + "\n")  # echo scripted answers into the transcript
        return line

    coordinator = Coordinator(read, write)
    station, rig, view, relay_port = None, None, None, None
    try:
        if args.haptic == "sim://" and args.robot == "sim://robot":
            rig = RehearsalStation(rig_options(args), participant_params(args))
            rig.open()
            station = rig.poke_and_describe
            areas = rig.areas
        elif args.haptic == "none":
            areas = blind_areas()
        else:
            rig = BackgroundSession(args.haptic, args.robot, rig_options(args))
            if args.live is not None:  # the loop's own live view, relayed to the experimenter's screen
                relay_port = _free_port()
                rig.argv += ["--live", str(relay_port)]
            rig.open()
            areas = blind_areas()
        if args.live is not None:
            view = _study_live_view(args, areas, relay_port)
            print(f"live view: ws://{args.live_host}:{view.port} (Foxglove WebSocket; the experimenter's screen)",
                  flush=True)
        result = run_human_study(args.state, args.seed, args.participants, areas, coordinator, station,
                                 on_step=view.on_step if view is not None else None)
    finally:
        if view is not None:
            view.close()
        if rig is not None:
            rig.close()
    if result is None:
        return 1
    print()
    print(result.table())
    _write_results(args, result)
    return 0
