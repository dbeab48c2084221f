"""`teleop bench blind-jnd`: share of simulated participants ranking the four areas correctly, against the
stiffness JND, through the whole simulated chain (default 100 participants per point).

Every participant is run at every JND on the same pad layout, presentation order and pushes (common random
numbers: a participant's k-th poke of a zone is the same push whatever the JND). A poke the participant
already made at another JND is replayed from the trace the chain rendered the first time (exactly the same
push, so the same trace up to the chain's history); only the extra pokes an unsure participant asks for
are simulated anew. The curve therefore isolates the perceptual noise from the chain.
"""

from __future__ import annotations

import math
import sys

DEFAULT_JNDS = "0.05,0.1,0.15,0.23,0.3,0.4,0.6,0.8"


def register(subparsers) -> None:
    from teleop.commands.blind_test import add_rig_options, positive_int

    p = subparsers.add_parser("blind-jnd", help="correct-ranking share vs stiffness JND (blind test, simulated)")
    p.add_argument("--participants", type=positive_int, default=100, metavar="N", help="participants per point")
    p.add_argument("--jnd", default=DEFAULT_JNDS, metavar="J1,J2,...",
                   help=f"JNDs as Weber fractions (default {DEFAULT_JNDS})")
    p.add_argument("--seed", type=int, default=0)
    add_rig_options(p)
    p.add_argument("--json", metavar="PATH", help="write the curve as JSON")
    p.add_argument("--plot", metavar="PATH", help="write the curve as a PNG")
    p.set_defaults(func=run, jnd_list=None)


def parse_jnds(text: str) -> list:
    from teleop.commands.blind_test import parse_fraction
    from teleop.errors import InputError

    out = []
    for part in filter(None, (s.strip() for s in str(text).split(","))):
        try:
            out.append(parse_fraction(part))
        except Exception as exc:  # argparse.ArgumentTypeError
            raise InputError(f"--jnd '{text}': {exc}") from None
    if not out:
        raise InputError(f"--jnd '{text}': expected a comma-separated list such as 0.1,0.23,0.4")
    return sorted(set(out))


def wilson(k: int, n: int, z: float = 1.96) -> tuple:
    """95 % Wilson score interval of a proportion k/n."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def jnd_curve(rig, jnds, participants: int, seed: int, base_params, progress=None) -> dict:
    """{jnd: StudyResult} for every JND, each participant run on the same layout and pushes."""
    import dataclasses

    from teleop.protocols.blind.study import StudyResult, coordinator_draws, record_from, run_participant

    areas = tuple(rig.areas)
    records = {j: [] for j in jnds}
    for p in range(1, participants + 1):
        layout, order = coordinator_draws(seed, p, areas)
        rig.arrange(layout)
        cache = {}

        def palpate(zone, request, _order=order, _cache=cache):
            key = (zone, request.depth, request.speed)  # the n-th push of a zone is the same at every JND
            if key not in _cache:
                _cache[key] = rig.poke(_order[zone], request)
            return _cache[key]

        for j in jnds:
            params = dataclasses.replace(base_params, jnd=j)
            answers, ranking, ratings, person = run_participant(palpate, len(areas), params, (seed, p))
            records[j].append(record_from(p, layout, order, answers, ranking, ratings, person))
        if progress is not None:
            progress()
    return {j: StudyResult(areas=areas, records=tuple(records[j])) for j in jnds}


def run(args) -> int:
    from tqdm import tqdm

    from teleop.commands.blind_test import participant_params, rig_options
    from teleop.outputs import save_figure, write_json
    from teleop.protocols.blind.rig import SimRig

    jnds = parse_jnds(args.jnd)
    args.jnd = None
    base = participant_params(args)
    options = rig_options(args)
    with SimRig(options) as rig, tqdm(total=args.participants, desc="blind-jnd", unit="participant",
                                      file=sys.stderr, disable=not sys.stderr.isatty()) as bar:
        curve = jnd_curve(rig, jnds, args.participants, args.seed, base, progress=bar.update)
        rig_desc = rig.describe()
    points = []
    print(f"{'JND':>6}  {'correct':>8}  {'95% CI':>15}  {'tau mean':>8}  {'pokes/participant':>17}")
    for j in jnds:
        res = curve[j]
        n = len(res.records)
        k = sum(r.ranking == res.truth for r in res.records)
        lo, hi = wilson(k, n)
        pokes = sum(r.pokes for r in res.records) / n
        points.append({"jnd": j, "participants": n, "correct_ranking_rate": k / n, "ci95": [lo, hi],
                       "kendall_tau_mean": res.kendall_tau_mean, "pokes_mean": pokes})
        print(f"{j:6.2f}  {k / n:8.2f}  [{lo:5.2f}, {hi:5.2f}]  {res.kendall_tau_mean:8.3f}  {pokes:17.1f}")
    out = {"participants": args.participants, "seed": args.seed, "points": points,
           "participant_params": dataclasses_asdict(base), "rig": rig_desc}
    if args.json:
        write_json(args.json, out)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        x = [pt["jnd"] * 100 for pt in points]
        y = [pt["correct_ranking_rate"] for pt in points]
        err = [[pt["correct_ranking_rate"] - pt["ci95"][0] for pt in points],
               [pt["ci95"][1] - pt["correct_ranking_rate"] for pt in points]]
        ax.errorbar(x, y, yerr=err, fmt="o-", capsize=3)
        ax.axvline(23, color="grey", ls="--", lw=0.8, label="Jones & Hunter 1990: 23 %")
        ax.set_xlabel("stiffness JND [%]")
        ax.set_ylabel("share ranking all four areas correctly")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(f"{args.participants} simulated participants per point"
                     + ("" if options.compensation else " (no compensation)"))
        ax.legend()
        save_figure(fig, args.plot)
    return 0


def dataclasses_asdict(obj) -> dict:
    from dataclasses import asdict

    return asdict(obj)
