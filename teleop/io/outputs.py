"""Result files: checked before the work starts, written atomically (complete or absent, never half-written),
with the permissions the user's umask gives a new file (like any other program's output, so a lab's shared
folder can read them).

The temporary file is created with ``os.open(..., 0o666)`` rather than ``tempfile.mkstemp``: mkstemp
creates it 0600 whatever the umask, and the rename would carry that mode onto the result.
"""

from __future__ import annotations

import json
import os
import secrets
from pathlib import Path
from typing import Any, Callable

import numpy as np

from teleop.core.errors import InputError


def _default(obj: Any):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


# The figure formats `save_figure` writes, by file suffix (no suffix: PNG).
FIGURE_FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg", "": "png"}


def same_file(a: str | Path, b: str | Path) -> bool:
    """True when paths `a` and `b` name one existing file (the same path, a link to it, or a hard link)."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet): no file to overwrite
        return False


def _probe(parent: Path, missing: Path | None) -> str | None:
    """Why nothing can be created in directory `parent` (first directory to create: `missing`), or None.

    A probe is made and removed at once: the permission bits say nothing for root, nor on a read-only or
    virtual file system (/proc)."""
    try:
        if missing is not None:
            os.mkdir(missing)
            os.rmdir(missing)
        else:
            os.unlink(_create_temp(parent / "probe"))
    except OSError as exc:
        return f"cannot be created: {missing or parent}: {exc.strerror or exc}"
    return None


def output_problem(path: str | Path, directory: bool = False) -> str | None:
    """Why `path` cannot be written as a result file (or, with `directory`, made a directory), or None.

    The path must not be an existing directory (a file) or file (a directory), and its nearest existing
    ancestor must be a directory this process may write into (missing directories are created at write time;
    a probe file or directory is created there and removed at once to find out).
    """
    path = Path(path)
    if str(path) == "" or path.name in ("", ".", ".."):
        return "expected a file name"
    if path.exists():
        if directory and not path.is_dir():
            return "exists and is not a directory"
        if not directory and path.is_dir():
            return "is a directory, expected a file name"
        if not os.access(path, os.W_OK):
            return "is not writable"
        return None
    parent, missing = path.absolute().parent, None
    while not parent.exists():
        if parent.parent == parent:
            break
        parent, missing = parent.parent, parent
    if not parent.is_dir():
        return f"cannot be created: {parent} is not a directory"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"cannot be created: directory {parent} is not writable"
    return _probe(parent, missing)


def check_output(path: str | Path, what: str = "output") -> Path:
    """`path` if a result can be written there, else an InputError naming it (call before the work starts)."""
    problem = output_problem(path)
    if problem:
        raise InputError(f"{what} {path}: {problem}")
    return Path(path)


def _create_temp(path: Path) -> Path:
    """A new empty file beside `path`, created with mode 0666 minus the umask."""
    for _ in range(100):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}{path.suffix or '.tmp'}")
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"{path}: no free temporary name beside it")


def atomic_write(path: str | Path, write: Callable[[Path], None]) -> Path:
    """Call `write(tmp_path)` then rename onto `path`; on failure nothing is left behind.

    The result has the mode a new file gets under the current umask (0644 under the usual 022).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _create_temp(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def write_text_synced(path: str | Path, text: str) -> Path:
    """Write `text` atomically and durably (temp file, fsync, rename): after a crash the file is either the
    old one or the whole new one, never a part (resumable state, campaign results)."""
    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())

    return atomic_write(path, write)


def dumps_json(obj: Any, sort_keys: bool = False, compact: bool = False) -> str:
    """Deterministic JSON text: insertion order (the documented order) unless `sort_keys`; floats as
    Python's shortest round-trip repr; indented, or on one line without spaces if `compact`."""
    layout = {"separators": (",", ":")} if compact else {"indent": 2}
    return json.dumps(obj, default=_default, allow_nan=False, sort_keys=sort_keys, **layout) + "\n"


def write_json(path: str | Path, obj: Any, sort_keys: bool = False) -> Path:
    """Write `obj` as JSON atomically. NaN/inf are refused (they are not JSON)."""
    text = dumps_json(obj, sort_keys)
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def save_figure(fig, path: str | Path, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically in the format its suffix names (FIGURE_FORMATS) and close it."""
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fmt = FIGURE_FORMATS.get(Path(path).suffix.lower())
    try:
        if fmt is None:
            raise InputError(f"{path}: a figure is written as {', '.join(s for s in FIGURE_FORMATS if s)}, "
                             f"not {Path(path).suffix}")
        return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=fmt, bbox_inches="tight"))
    finally:
        plt.close(fig)
