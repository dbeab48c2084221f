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
    from teleop.argtypes import positive_int
    from teleop.commands.blind_test import add_rig_options

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
    """{jnd: StudyResult} for every JND, each participant run on the same layout and pushes.

    progress(partial), optional, is called after each participant with the curve so far."""
    import dataclasses

    from teleop.protocols.blind.study import StudyResult, coordinator_draws, record_from, run_participant

    areas = tuple(rig.areas)
    records = {j: [] for j in jnds}
    for p in range(1, participants + 1):
        layout, order = coordinator_draws(seed, p, areas)
        rig.arrange(layout)
        cache = {}

        def palpate(zone, request, _order=order, _cache=cache):
            key = (zone, request.depth, request.speed, request.force)  # the n-th push of a zone: same at every JND
            if key not in _cache:
                _cache[key] = rig.poke(_order[zone], request)
            return _cache[key]

        for j in jnds:
            params = dataclasses.replace(base_params, jnd=j)
            answers, ranking, ratings, person = run_participant(palpate, len(areas), params, (seed, p))
            records[j].append(record_from(p, layout, order, answers, ranking, ratings, person))
        if progress is not None:
            progress({j: StudyResult(areas=areas, records=tuple(records[j])) for j in jnds})
    return {j: StudyResult(areas=areas, records=tuple(records[j])) for j in jnds}


def curve_points(curve: dict) -> list:
    """Per JND: participants, correct-ranking share with its 95 % Wilson interval, mean tau, pokes."""
    points = []
    for j in sorted(curve):
        res = curve[j]
        n = len(res.records)
        k = sum(r.ranking == res.truth for r in res.records)
        lo, hi = wilson(k, n)
        points.append({"jnd": j, "participants": n, "correct_ranking_rate": k / n, "ci95": [lo, hi],
                       "kendall_tau_mean": res.kendall_tau_mean,
                       "pokes_mean": sum(r.pokes for r in res.records) / n})
    return points


def run(args) -> int:
    from tqdm import tqdm

    from teleop.commands.blind_test import participant_params, rig_options
    from teleop.outputs import save_figure, write_json
    from teleop.protocols.blind.rig import SimRig

    jnds = parse_jnds(args.jnd)
    args.jnd = None
    base = participant_params(args)
    options = rig_options(args)

    def document(points, complete: bool, rig_desc) -> dict:
        return {"participants": args.participants, "seed": args.seed, "complete": complete, "points": points,
                "participant_params": dataclasses_asdict(base), "rig": rig_desc}

    with SimRig(options) as rig, tqdm(total=args.participants, desc="blind-jnd", unit="participant",
                                      file=sys.stderr, disable=not sys.stderr.isatty()) as bar:
        rig_desc = rig.describe()

        def progress(partial):
            bar.update()
            done = len(next(iter(partial.values())).records)
            if args.json and done % 10 == 0 and done < args.participants:  # a long run leaves usable results
                write_json(args.json, document(curve_points(partial), False, rig_desc))

        curve = jnd_curve(rig, jnds, args.participants, args.seed, base, progress=progress)
    points = curve_points(curve)
    print(f"{'JND':>6}  {'correct':>8}  {'95% CI':>15}  {'tau mean':>8}  {'pokes/participant':>17}")
    for pt in points:
        lo, hi = pt["ci95"]
        print(f"{pt['jnd']:6.2f}  {pt['correct_ranking_rate']:8.2f}  [{lo:5.2f}, {hi:5.2f}]  "
              f"{pt['kendall_tau_mean']:8.3f}  {pt['pokes_mean']:17.1f}")
    if args.json:
        write_json(args.json, document(points, True, rig_desc))
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        x = [pt["jnd"] * 100 for pt in points]
        y = [pt["correct_ranking_rate"] for pt in points]
        err = [[pt["correct_ranking_rate"] - pt["ci95"][0] for pt in points],
               [pt["ci95"][1] - pt["correct_ranking_rate"] for pt in points]]
        ax.errorbar(x, y, yerr=err, fmt="o-", capsize=3, label="all four in the right order")
        ax.plot(x, [pt["kendall_tau_mean"] for pt in points], "s--", label="mean Kendall tau")
        ax.axvline(23, color="grey", ls="--", lw=0.8, label="Jones & Hunter 1990: 23 %")
        ax.set_xlabel("stiffness JND [%]")
        ax.set_ylabel("share / tau")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(f"{args.participants} simulated participants per point"
                     + ("" if options.compensation else " (no compensation)"))
        ax.legend()
        save_figure(fig, args.plot)
    return 0


def dataclasses_asdict(obj) -> dict:
    from dataclasses import asdict

    return asdict(obj)
