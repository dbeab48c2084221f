"""The result store: a directory holding one JSON file per finished task, written atomically as it completes.

Layout of DIR:
    tasks/<task id>.json    {"task", "kind", "label", "identity", "teleop_version", "result"}: a finished
                            task (one line, sorted keys, floats as shortest round-trip repr: the same
                            result is the same bytes)
    failed/<task id>.json   {"task", "kind", "label", "identity", "error", "traceback"}: the last failure
                            of a task not yet finished (removed when it finishes)
    runs.jsonl              one line per run: scheduler, counts, wall and task times (not results)
    .lock                   held (flock) by the run using DIR; the kernel drops it when that process dies

A task is done when its file is in tasks/; the file appears by rename, so it is complete or absent even
when the run is killed (SIGKILL) while writing it. Writes are fsynced before the rename, so a machine that
loses power keeps only complete results too. A file that does not parse or holds another identity (it
cannot happen short of a disk fault) counts as not done and is redone.
"""

from __future__ import annotations

import fcntl
import json
import os
from pathlib import Path

from teleop import __version__
from teleop.apps.campaign.identity import Task
from teleop.core.errors import InputError
from teleop.io.outputs import dumps_json, write_text_synced


def _write_synced(path: Path, text: str) -> None:
    write_text_synced(path, text)


class ResultStore:
    """Finished and failed tasks under `root` (see the module docstring)."""

    def __init__(self, root: str | Path):
        self.root = Path(root)
        self.tasks_dir = self.root / "tasks"
        self.failed_dir = self.root / "failed"
        self._lock = None

    def __enter__(self) -> "ResultStore":
        self.lock()
        return self

    def __exit__(self, *exc) -> None:
        self.unlock()

    def lock(self) -> None:
        """Hold DIR/.lock for this process; another live run on DIR is an InputError."""
        self.tasks_dir.mkdir(parents=True, exist_ok=True)
        self.failed_dir.mkdir(parents=True, exist_ok=True)
        fh = open(self.root / ".lock", "a+")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.close()
            raise InputError(f"{self.root}: another `teleop campaign run` is using this directory") from None
        self._lock = fh
        for stale in (*self.tasks_dir.glob(".*"), *self.failed_dir.glob(".*")):  # temp files of a killed run
            stale.unlink(missing_ok=True)

    def unlock(self) -> None:
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    def _path(self, task: Task) -> Path:
        return self.tasks_dir / f"{task.id}.json"

    def done_ids(self) -> set:
        """Ids of the tasks with a result file (one directory listing, whatever the number of tasks)."""
        if not self.tasks_dir.is_dir():
            return set()
        return {n[:-5] for n in os.listdir(self.tasks_dir) if n.endswith(".json") and not n.startswith(".")}

    def load(self, task: Task):
        """The stored result of `task`, or None when it is not (validly) there."""
        try:
            doc = json.loads(self._path(task).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if not isinstance(doc, dict) or doc.get("identity") != task.identity or "result" not in doc:
            return None
        return doc["result"]

    def save(self, task: Task, result) -> None:
        """Write `task`'s result atomically and forget an earlier failure of it."""
        doc = {"task": task.id, "kind": task.kind, "label": task.label, "identity": task.identity,
               "teleop_version": __version__, "result": result}
        _write_synced(self._path(task), dumps_json(doc, sort_keys=True, compact=True))
        (self.failed_dir / f"{task.id}.json").unlink(missing_ok=True)

    def forget(self, task: Task) -> None:
        """Remove `task`'s result file (one that does not load: the next run does the task again)."""
        self._path(task).unlink(missing_ok=True)

    def save_failure(self, task: Task, error: str, trace: str = "") -> None:
        """Record `task`'s failure: its error line and traceback, beside its identity (the parameters)."""
        doc = {"task": task.id, "kind": task.kind, "label": task.label, "identity": task.identity,
               "error": error, "traceback": trace}
        _write_synced(self.failed_dir / f"{task.id}.json", dumps_json(doc, sort_keys=True))

    def failure(self, task: Task):
        """The error text of `task`'s last failure, or None."""
        try:
            return json.loads((self.failed_dir / f"{task.id}.json").read_text(encoding="utf-8"))["error"]
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def log_run(self, record: dict) -> None:
        """Append one run's record (times and counts) to runs.jsonl."""
        self.root.mkdir(parents=True, exist_ok=True)
        with open(self.root / "runs.jsonl", "a", encoding="utf-8") as fh:
            fh.write(json.dumps(record, sort_keys=True) + "\n")
