"""Campaign kind `diagnose`: a fleet of recordings, each diagnosed (teleop.diagnosis: where simulation and
recording differ, which named effect explains it, the held-out fit once it is modelled), and the findings
tabulated effect x recording.

    [[recordings]]                       # one table per group of files sharing a column map
    paths = ["rig_a/*.csv", "b.csv"]     # globs, relative to the campaign file
    map = "mrdlab"                       # optional: a shipped column map or a .toml path
    holdout = 0.4                        # optional: fraction at the end scoring the models (0.4)
    baseline = "default"                 # optional: what the simulation already holds ("lossless", "a,b")
    sindy = false                        # optional: also score the PySINDy peer

A task is one recording; its identity holds the file's absolute path and the SHA-256 of its bytes (an
edited recording is diagnosed again), the map, the holdout, the baseline effects, sindy and the seed. The seed drives the fits' extra
starts and is the campaign seed on every recording, as `teleop diagnose --seed` does, so a campaign's
report of a file is the one `teleop diagnose FILE --seed S` gives.
"""

from __future__ import annotations

import csv
import dataclasses
import glob
import hashlib
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from teleop.apps.campaign.identity import Task
from teleop.apps.campaign.plots import findings_heatmap
from teleop.apps.campaign.scheduler import open_scheduler
from teleop.apps.campaign.task_progress import TaskProgress
from teleop.core.config import check_keys, get_number
from teleop.core.errors import InputError
from teleop.diagnosis.diagnose import HOLDOUT, baseline_effects, diagnose
from teleop.diagnosis.plot import ATTRIBUTION
from teleop.io.outputs import atomic_write, save_figure
from teleop.io.recording_io import MAX_INPUT_MB, builtin_map, read_recording

KIND = "diagnose"


@dataclass(frozen=True)
class RecordingEntry:
    """One file to diagnose: absolute path, SHA-256 of its bytes, column map (None: interchange CSV;
    else a shipped name or an absolute .toml path), holdout fraction, the baseline's catalogue effects
    (teleop.diagnosis.diagnose.baseline_effects) and whether the PySINDy peer is scored too."""

    path: str
    sha256: str
    map: str | None
    holdout: float
    baseline: tuple
    sindy: bool


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def parse(doc: dict, where: str, base_dir: Path) -> tuple:
    """The [[recordings]] tables of the file `where`: a tuple of RecordingEntry, in glob order, each file once."""
    check_keys(doc, ("recordings",), where)
    groups = doc.get("recordings")
    if not isinstance(groups, list) or not groups or not all(isinstance(g, dict) for g in groups):
        raise InputError(f"{where}: expected one or more [[recordings]] tables with paths = [\"*.csv\", ...]")
    out, seen = [], set()
    for i, g in enumerate(groups, start=1):
        at = f"{where} [[recordings]] #{i}"
        check_keys(g, ("paths", "map", "holdout", "baseline", "sindy"), at)
        paths = g.get("paths")
        if isinstance(paths, str):
            paths = [paths]
        if not isinstance(paths, list) or not paths or not all(isinstance(p, str) for p in paths):
            raise InputError(f"{at}: key 'paths' must be a list of file names or globs")
        holdout = get_number(g, "holdout", at, default=HOLDOUT, positive=True)
        if holdout >= 1:
            raise InputError(f"{at}: key 'holdout' must be a fraction in (0, 1), got {holdout}")
        spec = g.get("baseline", "default")
        if not isinstance(spec, str):
            raise InputError(f"{at}: key 'baseline' must be 'default', 'lossless' or a comma list of effects")
        try:
            baseline = baseline_effects(spec)
        except InputError as exc:
            raise InputError(f"{at}: {exc}") from None
        sindy = g.get("sindy", False)
        if not isinstance(sindy, bool):
            raise InputError(f"{at}: key 'sindy' must be true or false, got {sindy!r}")
        cmap = g.get("map")
        if cmap is not None:
            if not isinstance(cmap, str):
                raise InputError(f"{at}: key 'map' must be a shipped map name or a .toml path, got {cmap!r}")
            if cmap.endswith(".toml"):
                cmap_path = (base_dir / cmap).resolve()
                if not cmap_path.is_file():
                    raise InputError(f"{at}: map {cmap}: file not found ({cmap_path})")
                cmap = str(cmap_path)
            else:
                try:
                    builtin_map(cmap)
                except InputError as exc:
                    raise InputError(f"{at}: {exc}") from None
        for pattern in paths:
            matches = sorted(glob.glob(str(base_dir / pattern)))
            files = [Path(m).resolve() for m in matches if Path(m).is_file()]
            if not files:
                raise InputError(f"{at}: '{pattern}' matches no file (relative to {base_dir})")
            for f in files:
                if str(f) not in seen:
                    seen.add(str(f))
                    out.append(RecordingEntry(str(f), _digest(f), cmap, holdout, tuple(baseline), sindy))
    return tuple(out)


def tasks(campaign) -> list:
    return [Task(KIND, {"recording": r.path, "sha256": r.sha256, "map": r.map, "holdout": r.holdout,
                        "baseline": list(r.baseline), "sindy": r.sindy, "seed": campaign.seed}, r.path)
            for r in campaign.study]


def execute(identity: dict) -> dict:
    """Diagnose one recording (on a worker): the report of `teleop diagnose` (Diagnosis.as_dict)."""
    rec = read_recording(identity["recording"], identity["map"])
    return diagnose(rec, identity["holdout"], seed=identity["seed"], baseline=tuple(identity["baseline"]),
                    sindy=identity["sindy"]).as_dict()


def _diagnose_file(item):
    """Read and diagnose one file where the scheduler runs it: item = (path, map, holdout, max_mb, options)."""
    path, cmap, holdout, max_mb, options = item
    return diagnose(read_recording(path, cmap, max_mb), holdout, **options)


def diagnose_files(paths: list, column_map, holdout: float, scheduler: str, max_mb: float | None = MAX_INPUT_MB,
                   **options) -> list:
    """Diagnosis of each of `paths` (in that order), each file read and diagnosed where `scheduler` runs
    tasks (`teleop diagnose REC... --scheduler`), as `diagnose(read_recording(path, column_map), holdout,
    **options)` (seed, baseline, ...) would give here. Workers get absolute paths; each Diagnosis comes
    back with the path as given. The first file that fails is an InputError naming it."""
    cmap = column_map
    if cmap is not None and str(cmap).endswith(".toml"):
        cmap = str(Path(cmap).absolute())
    items = [(str(Path(p).absolute()), cmap, holdout, max_mb, options) for p in paths]
    done = {}
    with open_scheduler(scheduler) as sched, TaskProgress(len(items), "diagnose") as progress:
        for item, outcome in sched.run(_diagnose_file, items):
            if not outcome.ok:  # a malformed file's InputError already names it
                err = outcome.error
                raise InputError(err.split(": ", 1)[1] if err.startswith("InputError: ") else f"{item[0]}: {err}")
            done[item[0]] = outcome.value
            progress.update()
    return [dataclasses.replace(d, rec=dataclasses.replace(d.rec, path=str(Path(p))))
            for p, d in zip(paths, (done[i[0]] for i in items))]


def findings_matrix(reports: list) -> tuple:
    """(columns, matrix): columns 'effect on channel' in order of first appearance, matrix (recordings,
    columns) of held-out improvements, NaN where the effect was not found on that recording."""
    columns = []
    for rep in reports:
        for f in rep["findings"]:
            c = f"{f['effect']} on {f['channel']}"
            if c not in columns:
                columns.append(c)
    m = np.full((len(reports), len(columns)), np.nan)
    for i, rep in enumerate(reports):
        for f in rep["findings"]:
            m[i, columns.index(f"{f['effect']} on {f['channel']}")] = f["improvement"]
    return columns, m


def summarise(campaign, load) -> dict:
    """Per recording (campaign order) its findings (effect, channel, RMSE before/after, improvement) and
    what stayed unexplained, from the finished tasks' reports (load(task) -> report, None when not done)."""
    rows = []
    for task in tasks(campaign):
        rep = load(task)
        if rep is None:
            continue
        rows.append({"recording": task.identity["recording"],
                     "findings": [{k: f[k] for k in ("effect", "channel", "rmse_before", "rmse_after",
                                                     "improvement")} for f in rep["findings"]],
                     "unexplained": [{k: u.get(k) for k in ("channel", "correlate", "r2")}
                                     for u in rep["unexplained"]]})
    columns, m = findings_matrix(rows)
    return {"kind": KIND, "seed": campaign.seed, "recordings": rows, "columns": columns,
            "improvement": [[None if not math.isfinite(v) else float(v) for v in row] for row in m]}


def _short_names(paths: list) -> list:
    """The shortest trailing parts of each path that tell the recordings apart (file names if they do)."""
    parts = [Path(p).parts for p in paths]
    for k in range(1, max(len(x) for x in parts) + 1):
        names = [str(Path(*x[-k:])) for x in parts]
        if len(set(names)) == len(names):
            return names
    return list(paths)


def table(summary: dict) -> str:
    """Effect x recording: held-out improvement (x) where found, '-' where not."""
    rows = summary["recordings"]
    if not rows:
        return "(no recording finished)"
    names = _short_names([r["recording"] for r in rows])
    cols = summary["columns"]
    w = max(len(n) for n in names) + 2
    head = "recording".ljust(w) + "".join(f"{c:>{max(len(c), 8) + 2}}" for c in cols)
    lines = [head]
    for name, row in zip(names, summary["improvement"]):
        cells = "".join(f"{('-' if v is None else f'x{v:.2f}'):>{max(len(c), 8) + 2}}" for c, v in zip(cols, row))
        lines.append(name.ljust(w) + cells)
    return "\n".join(lines)


def findings_csv(summary: dict) -> str:
    """CSV text: one row per recording, one column per effect on a channel (held-out improvement, empty
    where not found)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["recording", *summary["columns"]])
    for r, row in zip(summary["recordings"], summary["improvement"]):
        w.writerow([r["recording"], *("" if v is None else repr(v) for v in row)])
    return buf.getvalue()


def write_outputs(summary: dict, out_dir: Path) -> list:
    """findings.csv and findings.png (heat map of the held-out improvements)."""
    out_dir = Path(out_dir)
    text = findings_csv(summary)
    paths = [atomic_write(out_dir / "findings.csv", lambda tmp: tmp.write_text(text, encoding="utf-8"))]
    if summary["recordings"] and summary["columns"]:
        m = np.array([[np.nan if v is None else v for v in row] for row in summary["improvement"]], dtype=float)
        names = _short_names([r["recording"] for r in summary["recordings"]])
        fig = findings_heatmap(names, summary["columns"], m,
                               f"teleop campaign (diagnose): {len(names)} recordings, held-out improvement "
                               f"of each identified effect" + (f"\n{ATTRIBUTION}" if any(
                                   "mrdlab" in r["recording"].lower() for r in summary["recordings"]) else ""))
        paths.append(save_figure(fig, out_dir / "findings.png"))
    return paths
