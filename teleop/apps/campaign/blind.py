"""Campaign kind `blind-jnd`: a grid of simulated blind studies, each a correct-ranking curve against the
participants' stiffness JND (seed 000 §5.2 through the whole simulated chain, teleop.apps.protocols.blind).

    [study]
    participants = 20             # per grid point
    participants_per_task = 5     # a task runs this many participants at every JND (default 5)
    jnd = [0.1, 0.23, 0.4, 0.8]   # the curve's points: Weber fractions (or "23%")
    [rig]                         # fixed teleop.apps.protocols.blind.rig.RigOptions fields, SI (not seed)
    robot_substeps = 4
    [participant]                 # fixed ParticipantParams fields, SI (not jnd)
    force = 0.2
    [grid]                        # RigOptions or ParticipantParams fields -> values; the grid is the product
    force_scale = [0.05, 0.1]
    kalman_bandwidth = [20.0, 80.0]

The rig option `geometry` names a geometry TOML (teleop.core.geometry.load_geometry; a lab's own robot), relative
to the campaign file, in [rig] or as a [grid] axis of several robots; it is read (checked) when the campaign is
loaded, and a task's identity holds the file's SHA-256, so an edited file is a new task.

Random streams: participant p of a campaign seeded s draws (study seed, rig seed) from
identity.seeds(s, p): the study seed gives the pad layout and presentation order
(study.coordinator_draws) and the participant's own draws (person, pushes, perception noise), the rig seed
the chain's (stylus tremor, FSR noise; one fresh rig per participant). Participant p is therefore the same
simulated person at every grid point and every JND (common random numbers): differences between grid
points are the chain's, not the sample's. Within a participant, a push already made at another JND is
replayed from the trace the chain rendered the first time (the same push); only the extra pokes of an
unsure participant are simulated anew.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

from teleop.apps.argtypes import jnd_fraction
from teleop.apps.campaign.identity import Task, seeds
from teleop.apps.campaign.plots import jnd_curves_figure
from teleop.apps.campaign.values import coerce, get_int
from teleop.apps.protocols.blind.participants import ParticipantParams
from teleop.apps.protocols.blind.rig import RigOptions, SimRig, blind_areas, rig_dict
from teleop.apps.protocols.blind.study import (ParticipantRecord, StudyResult, coordinator_draws, record_from,
                                               run_participant)
from teleop.core.config import check_keys
from teleop.core.errors import InputError
from teleop.core.geometry import load_geometry
from teleop.io.outputs import save_figure
from teleop.loop.warm import warm_up

KIND = "blind-jnd"
PER_TASK = 5  # participants per task by default: a few seconds of work each


@dataclass(frozen=True)
class GridPoint:
    """One study setting: `params` (the grid's values at this point, in file order), and the full
    RigOptions (without seed) and ParticipantParams (without jnd) as dicts."""

    params: dict
    rig: dict
    participant: dict

    @property
    def label(self) -> str:
        return point_label(self.params)


def point_label(params: dict) -> str:
    """'force_scale=0.1, kalman_bandwidth=80.0' (or 'default' for a campaign without a grid)."""
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "default"


@dataclass(frozen=True)
class BlindStudy:
    """participants per grid point, participants per task, the JNDs (sorted) and the grid points."""

    participants: int
    per_task: int
    jnds: tuple
    points: tuple


def _fields(cls, leave_out: str) -> dict:
    return {f.name: str(f.type) for f in dataclasses.fields(cls) if f.name != leave_out}


def rig_fields() -> dict:
    return _fields(RigOptions, "seed")


def participant_fields() -> dict:
    return _fields(ParticipantParams, "jnd")


def jnd_values(items, where: str) -> list:
    """Sorted distinct JNDs (Weber fractions) from numbers or text ('0.23', '23%')."""
    out = []
    for item in items:
        if isinstance(item, bool) or not isinstance(item, (int, float, str)):
            raise InputError(f"{where}: expected JNDs such as 0.1 or \"23%\", got {item!r}")
        try:
            out.append(jnd_fraction(str(item)))
        except argparse.ArgumentTypeError as exc:
            raise InputError(f"{where}: {exc}") from None
    if not out:
        raise InputError(f"{where}: expected at least one JND, such as [0.1, 0.23, 0.4]")
    return sorted(set(out))


def make_point(params: dict, rig: dict, participant: dict, where: str) -> GridPoint:
    """A GridPoint with the options checked by their dataclasses (an InputError names `where`)."""
    try:
        options = RigOptions(**rig)
        person = ParticipantParams(**participant)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    full_rig = {k: v for k, v in rig_dict(options).items() if k != "seed"}
    full_person = {k: v for k, v in dataclasses.asdict(person).items() if k != "jnd"}
    return GridPoint(params=dict(params), rig=full_rig, participant=full_person)


def parse(doc: dict, where: str, base_dir: Path) -> BlindStudy:
    """The [study], [rig], [participant] and [grid] tables (module docstring) of the file `where`."""
    check_keys(doc, ("study", "rig", "participant", "grid"), where)
    tables = {}
    for name in ("study", "rig", "participant", "grid"):
        t = doc.get(name, {})
        if not isinstance(t, dict):
            raise InputError(f"{where}: [{name}] must be a table")
        tables[name] = t
    study = tables["study"]
    check_keys(study, ("participants", "participants_per_task", "jnd"), f"{where} [study]")
    participants = get_int(study, "participants", f"{where} [study]", minimum=1)
    per_task = get_int(study, "participants_per_task", f"{where} [study]", default=PER_TASK, minimum=1)
    if "jnd" not in study or not isinstance(study["jnd"], list):
        raise InputError(f"{where} [study]: key 'jnd' must be a list of JNDs, such as [0.1, 0.23, 0.4]")
    jnds = jnd_values(study["jnd"], f"{where} [study] jnd")
    rf, pf = rig_fields(), participant_fields()
    check_keys(tables["rig"], rf, f"{where} [rig]")
    check_keys(tables["participant"], pf, f"{where} [participant]")
    check_keys(tables["grid"], {**rf, **pf}, f"{where} [grid]")
    fixed_rig = {k: coerce(rf[k], v, f"{where} [rig] {k}") for k, v in tables["rig"].items()}
    fixed_person = {k: coerce(pf[k], v, f"{where} [participant] {k}") for k, v in tables["participant"].items()}
    axes = {}
    for k, values in tables["grid"].items():
        if k in fixed_rig or k in fixed_person:
            raise InputError(f"{where} [grid] {k}: also given as a fixed value; give it in one place")
        if not isinstance(values, list) or not values:
            raise InputError(f"{where} [grid] {k}: expected a non-empty list of values")
        kind = rf.get(k) or pf[k]
        axes[k] = [coerce(kind, v, f"{where} [grid] {k}") for v in values]
    points = []
    for combo in itertools.product(*axes.values()):
        params = dict(zip(axes, combo))
        rig = {**fixed_rig, **{k: v for k, v in params.items() if k in rf}}
        if rig.get("geometry") is not None:
            rig["geometry"] = geometry_path(rig["geometry"], base_dir)
        person = {**fixed_person, **{k: v for k, v in params.items() if k in pf}}
        points.append(make_point(params, rig, person, f"{where} [grid] {params}"))
    labels = [p.label for p in points]
    if len(set(labels)) != len(labels):
        raise InputError(f"{where} [grid]: a value is listed twice (grid points must differ)")
    return BlindStudy(participants=participants, per_task=per_task, jnds=tuple(jnds), points=tuple(points))


def geometry_path(name: str, base_dir: Path) -> str:
    """The rig option `geometry` as an absolute path (a relative one is the campaign file's neighbour), the file
    read now: a missing file, a bad table or key is an InputError naming it."""
    path = Path(name) if Path(name).is_absolute() else Path(base_dir) / name
    load_geometry(path)
    return str(path.resolve())


def point_tasks(campaign) -> list:
    """[(GridPoint, [Task, ...])]: each point's participants in blocks of `per_task`."""
    s: BlindStudy = campaign.study
    out = []
    for point in s.points:
        blocks = []
        for first in range(1, s.participants + 1, s.per_task):
            last = min(first + s.per_task - 1, s.participants)
            identity = {"seed": campaign.seed, "rig": point.rig, "participant": point.participant,
                        "jnd": list(s.jnds), "participants": [first, last]}
            if point.rig.get("geometry") is not None:  # the file's content, not only its name, makes the task
                identity["geometry_sha256"] = hashlib.sha256(Path(point.rig["geometry"]).read_bytes()).hexdigest()
            blocks.append(Task(KIND, identity, f"{point.label}; participants {first}-{last}"))
        out.append((point, blocks))
    return out


def tasks(campaign) -> list:
    return [t for _, block in point_tasks(campaign) for t in block]


def participant_at_jnds(rig, participant: int, seed: int, jnds, base_params) -> list:
    """[ParticipantRecord] of participant `participant` at each JND on `rig` (study.Rig), all on the same
    layout and pushes (a push made at one JND is replayed from its trace at the others)."""
    areas = tuple(rig.areas)
    layout, order = coordinator_draws(seed, participant, areas)
    rig.arrange(layout)
    cache = {}

    def palpate(zone, request):
        key = (zone, request.depth, request.speed, request.force)  # the n-th push of a zone: same at every JND
        if key not in cache:
            cache[key] = rig.poke(order[zone], request)
        return cache[key]

    out = []
    for j in jnds:
        params = dataclasses.replace(base_params, jnd=j)
        answers, ranking, ratings, person = run_participant(palpate, len(areas), params, (seed, participant))
        out.append(record_from(participant, layout, order, answers, ranking, ratings, person))
    return out


def jnd_curve(rig, jnds, participants: int, seed: int, base_params, progress=None) -> dict:
    """{jnd: StudyResult} of participants 1..`participants` on one `rig` (study seed `seed` for all);
    progress(), optional, is called after each participant."""
    records = {j: [] for j in jnds}
    for p in range(1, participants + 1):
        for j, r in zip(jnds, participant_at_jnds(rig, p, seed, jnds, base_params)):
            records[j].append(r)
        if progress is not None:
            progress()
    return {j: StudyResult(areas=tuple(rig.areas), records=tuple(records[j])) for j in jnds}


def warm() -> None:
    """Once per worker process before its tasks: the compiled kernels (from numba's on-disk cache; compiled
    there if the cache is stale), so no task's time holds them (the modules a task uses come with this one)."""
    warm_up()


def execute(identity: dict) -> dict:
    """Run one task (on a worker): each participant of the block at every JND on a fresh simulated rig.
    Returns {"participants": [[record per JND] per participant]}."""
    options = RigOptions(**identity["rig"])
    base = ParticipantParams(**identity["participant"])
    first, last = identity["participants"]
    out = []
    for p in range(first, last + 1):
        study_seed, rig_seed = seeds(identity["seed"], p)
        with SimRig(dataclasses.replace(options, seed=rig_seed)) as rig:
            records = participant_at_jnds(rig, p, study_seed, identity["jnd"], base)
        out.append([record_to_json(r) for r in records])
    return {"participants": out}


def record_to_json(r) -> dict:
    """A ParticipantRecord as JSON values (record_from_json inverts it exactly)."""
    return {"participant": r.participant, "layout": list(r.layout), "order": list(r.order),
            "answers": [list(a) for a in r.answers], "ranking": list(r.ranking), "ratings": dict(r.ratings),
            "pokes": r.pokes, "slopes": {a: [float(k) for k in ks] for a, ks in r.slopes.items()},
            "aborted": r.aborted}


def record_from_json(d: dict):
    return ParticipantRecord(participant=d["participant"], layout=tuple(d["layout"]), order=tuple(d["order"]),
                             answers=tuple(tuple(a) for a in d["answers"]), ranking=tuple(d["ranking"]),
                             ratings=dict(d["ratings"]), pokes=d["pokes"],
                             slopes={a: list(ks) for a, ks in d["slopes"].items()}, aborted=d["aborted"])


def wilson(k: int, n: int, z: float = 1.96) -> tuple:
    """95 % Wilson score interval of a proportion k/n."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    # the interval holds p; at p = 0 or 1 its end is p only up to rounding (1 - 1e-16 at k = n): clamp
    return max(0.0, min(p, c - h)), min(1.0, max(p, c + h))


def curve_points(curve: dict) -> list:
    """Per JND of {jnd: StudyResult}: participants, correct-ranking share with its 95 % Wilson interval,
    mean Kendall tau, pokes per participant."""
    points = []
    for j in sorted(curve):
        res = curve[j]
        n = len(res.records)
        if n == 0:
            continue
        k = sum(r.ranking == res.truth for r in res.records)
        lo, hi = wilson(k, n)
        points.append({"jnd": j, "participants": n, "correct_ranking_rate": k / n, "ci95": [lo, hi],
                       "kendall_tau_mean": res.kendall_tau_mean,
                       "pokes_mean": sum(r.pokes for r in res.records) / n})
    return points


def summarise(campaign, load) -> dict:
    """The campaign's curves from the finished tasks' results (load(task) -> result, None when not done):
    per grid point its parameters, how many participants are done and the curve (curve_points). One
    point's results are in memory at a time."""
    s: BlindStudy = campaign.study
    areas = blind_areas()
    points = []
    for point, block in point_tasks(campaign):
        per_jnd = [[] for _ in s.jnds]
        for task in block:
            result = load(task)
            if result is None:
                continue
            for participant in result["participants"]:
                for i, rec in enumerate(participant):
                    per_jnd[i].append(record_from_json(rec))
        curve = {j: StudyResult(areas=areas, records=tuple(r)) for j, r in zip(s.jnds, per_jnd)}
        points.append({"params": point.params, "rig": point.rig, "participant": point.participant,
                       "participants_done": len(per_jnd[0]), "complete": len(per_jnd[0]) == s.participants,
                       "curve": curve_points(curve)})
    return {"kind": KIND, "seed": campaign.seed, "participants": s.participants, "jnd": list(s.jnds),
            "true_order": [a.name for a in areas], "points": points}


def curve_table(points: list) -> str:
    """One curve as text: JND, correct-ranking share, 95 % CI, mean tau, pokes per participant."""
    lines = [f"{'JND':>6}  {'correct':>8}  {'95% CI':>15}  {'tau mean':>8}  {'pokes/participant':>17}"]
    for pt in points:
        lo, hi = pt["ci95"]
        lines.append(f"{pt['jnd']:6.2f}  {pt['correct_ranking_rate']:8.2f}  [{lo:5.2f}, {hi:5.2f}]  "
                     f"{pt['kendall_tau_mean']:8.3f}  {pt['pokes_mean']:17.1f}")
    return "\n".join(lines)


def table(summary: dict) -> str:
    """The summary as text: per grid point its parameters and its curve."""
    out = []
    for pt in summary["points"]:
        out.append(f"{point_label(pt['params'])}: {pt['participants_done']} of {summary['participants']} "
                   "participants")
        out.append(curve_table(pt["curve"]) if pt["curve"] else "  (no participant finished)")
        out.append("")
    return "\n".join(out).rstrip()


# units of the grid's numeric axes as the figure shows them (RigOptions and ParticipantParams fields, SI;
# "-": dimensionless); a key not listed is shown as it is
GRID_UNITS = {"force_scale": "-", "motion_scale": "-", "gap": "m", "robot_substeps": "-", "settle": "s", "hold": "s",
              "release_speed": "m/s", "rest": "s", "tip_stiffness": "N/m", "kalman_bandwidth": "Hz", "jnd": "-",
              "depth": "m", "speed": "m/s", "person_spread": "-", "poke_spread": "-", "memory_noise": "-",
              "force_threshold": "N", "force": "N", "max_repeats": "-", "max_aborts": "-", "spacing": "-"}


def point_label_units(params: dict) -> str:
    """'force_scale 0.1 [-], kalman_bandwidth 80 [Hz]': the grid point with each value's unit (figures)."""
    return ", ".join(f"{k} {v:g} [{GRID_UNITS[k]}]" if k in GRID_UNITS and isinstance(v, (int, float))
                     and not isinstance(v, bool) else f"{k} {v}" for k, v in params.items()) or "default"


def rig_words(rigs: list) -> str:
    """'plant P, sensor S' of the rigs (dicts of rig_dict), each value or the values the grid spans."""
    def values(key, default):
        return "/".join(dict.fromkeys(str(r.get(key, default)) for r in rigs))
    return f"plant {values('plant', 'matched')}, sensor {values('sensor', 'fsr')}"


def write_outputs(summary: dict, out_dir: Path) -> list:
    """curves.png: correct-ranking share against JND per grid point, 95 % Wilson intervals."""
    curves = [(point_label_units(pt["params"]), pt["curve"]) for pt in summary["points"] if pt["curve"]]
    if not curves:
        return []
    n = summary["participants"]
    fig = jnd_curves_figure(curves, f"teleop campaign (blind-jnd): blind stiffness ranking against the JND, "
                                    f"simulated robot\n{rig_words([pt['rig'] for pt in summary['points']])}, "
                                    f"{n} simulated participants per grid point (seed {summary['seed']})")
    return [save_figure(fig, Path(out_dir) / "curves.png")]
