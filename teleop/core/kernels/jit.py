"""The one decorator of the compiled kernels: numba's `njit(cache=True)`, or the plain function without numba.

A kernel is written once, in the subset of Python numba compiles (floats, ints, tuples, numpy arrays, `math`);
with numba installed it runs compiled (machine code cached on disk, see `teleop.loop.warm`), without it
the same source runs as Python (`kernel.py_func` is that source in both cases). There is no second copy.

Cache location: `NUMBA_CACHE_DIR` if set and writable, else next to the sources (`__pycache__`), else a
per-user directory (~/.cache/numba). With none writable the kernels compile in memory at each start (one
warning line; numba itself would refuse to import them).

Cache freshness: a kernel's cached machine code holds the kernels it calls, compiled in, but numba checks
only the kernel's own file (its time stamp and size). A change in a callee's module (linalg.py under
geometry.py's forward kinematics) left the old code running from the cache (a fresh compile gave other
contact forces). So every kernel's cache is stamped with a hash of all the kernel sources
(`_kernels_stamp`): any change to any of them recompiles all, once. The kernel sources are this directory's
and the outer layers' kernel modules named in `OUTER_KERNELS` (paths, not imports: a scenes kernel that calls
these kernels, compiled into one call, is stamped with them, and they with it).
"""

from __future__ import annotations

import hashlib
import os
import sys

import numpy as np

try:  # numba is a dependency (pyproject.toml); TELEOP_NO_JIT=1 runs the same sources as Python
    if os.environ.get("TELEOP_NO_JIT"):
        raise ImportError("TELEOP_NO_JIT set")
    import numba as _numba
except ImportError:  # pragma: no cover - exercised with TELEOP_NO_JIT=1
    _numba = None

COMPILED = _numba is not None
_KERNEL_DIR = os.path.dirname(os.path.abspath(__file__))
_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(_KERNEL_DIR)))  # the project's root (teleop's parent)
#: kernel modules of the outer layers (paths from the project's root) whose kernels call these: stamped with them
OUTER_KERNELS = ("scenes/tendon_sheath_kernels.py", "scenes/fsr_sensor_kernels.py", "scenes/sim_robot_kernels.py")


def _kernel_files() -> list[tuple[str, str]]:
    """(name, path) of every kernel source file: this directory's *.py, then OUTER_KERNELS that exist."""
    files = [(name, os.path.join(_KERNEL_DIR, name)) for name in sorted(os.listdir(_KERNEL_DIR))
             if name.endswith(".py")]
    outer = [(rel, os.path.join(_ROOT, *rel.split("/"))) for rel in OUTER_KERNELS]
    return files + [(rel, path) for rel, path in outer if os.path.isfile(path)]


_STAMPED = {os.path.normcase(path) for _, path in _kernel_files()}  # the files whose caches carry the stamp


def _kernels_stamp() -> str:
    """sha256 of every kernel source file (`_kernel_files`, by name and content)."""
    h = hashlib.sha256()
    for name, path in _kernel_files():
        with open(path, "rb") as f:
            h.update(name.encode() + b"\0" + f.read())
    return h.hexdigest()


def _stamp_caches() -> None:
    """Put locators in front of numba's own that stamp the kernels' caches with `_kernels_stamp` (same cache
    places: NUMBA_CACHE_DIR, __pycache__, the per-user directory). Leaves numba's default (per-file stamps)
    if its caching internals are not the expected ones."""
    try:
        from numba.core import caching  # numba's internals: another layout keeps numba's own stamps

        bases = (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator)
        classes = caching.CacheImpl._locator_classes
    except (ImportError, AttributeError):  # pragma: no cover - another numba layout
        return
    stamp = _kernels_stamp()

    class _Stamped:
        def get_source_stamp(self):
            return stamp

        @classmethod
        def from_function(cls, py_func, py_file):
            if os.path.normcase(os.path.abspath(py_file)) not in _STAMPED:
                return None
            return super().from_function(py_func, py_file)

    classes[:0] = [type(f"Kernels{b.__name__}", (_Stamped, b), {}) for b in bases]


if _numba is not None:
    _stamp_caches()
    from numba.core import types as _types  # numba's structures (jit.structure)
    from numba.experimental import structref as _structref


_warned = []


def njit(fn=None, *, ieee_division: bool = False, inline: bool = False):
    """Compile `fn` with numba (nopython, cached on disk, no GIL held); without numba return it as is.

    ieee_division: a float division by zero gives inf or nan as in numpy (numba's error_model "numpy")
    instead of raising ZeroDivisionError as Python does; the kernel's code then carries no zero test per
    division (the same results for every nonzero divisor). For kernels whose divisors are never zero and
    whose callers check the outputs' finiteness anyway. `@njit(ieee_division=True)` (compiled only; the
    Python fallback raises as Python does).

    inline: the kernel's body is inlined into its compiled callers (numba's inline="always", at the IR: no call,
    no reference counting of its array arguments per call), for a small helper called per element of a hot
    loop with arrays among its arguments.

    With no writable cache location at all (read-only package, unwritable NUMBA_CACHE_DIR and home) numba
    refuses `cache=True`; the kernel then compiles in memory at its first call (one warning line)."""
    if fn is None:
        return lambda f: njit(f, ieee_division=ieee_division, inline=inline)
    if _numba is None:
        fn.py_func = fn
        return fn
    opts = {"nogil": True, "error_model": "numpy"} if ieee_division else {"nogil": True}
    if inline:
        opts["inline"] = "always"
    try:
        return _numba.njit(cache=True, **opts)(fn)
    except RuntimeError as exc:  # "cannot cache function ...: no locator available"
        if not _warned:
            print(f"teleop: warning: numba cache unavailable ({exc}); set NUMBA_CACHE_DIR to a writable "
                  "directory to keep compiled kernels between runs", file=sys.stderr)
            _warned.append(True)
        return _numba.njit(**opts)(fn)


_ND, _F64 = np.ndarray, np.dtype(np.float64)


def f64c(a) -> np.ndarray:
    """`a` as a float64 C-contiguous array, the type a kernel takes: a numpy array that already is one (a
    loop's own arrays, tick after tick; told by type and dtype identity) as it is, anything else converted
    (np.ascontiguousarray costs about 0.25 us a call even where it has nothing to do)."""
    if type(a) is _ND and a.dtype is _F64 and a.flags.c_contiguous:
        return a
    return np.ascontiguousarray(a, dtype=np.float64)


def bind(kernel, *args):
    """`kernel`'s compiled code for the numba types of `args` (compiled, or loaded from the cache, now if needed),
    called without numba's dispatch: a kernel call otherwise finds each argument's type and the matching
    compiled code at every call (about 0.04 us an argument; the loop's kernels take 8 to 26 each tick).

    For a call site whose arguments keep their types call after call (arrays it owns, floats, ints, tuples of
    floats): the bound code does not check them (an int64 array where a float64 one was bound is read as
    float64, a 2-D one as 1-D), so a caller that may be handed other types keeps the kernel itself for them.
    Without numba (or a numba whose dispatcher lacks these calls) the kernel itself."""
    if _numba is None:
        return kernel
    try:
        return kernel.compile(tuple(kernel.typeof_pyval(a) for a in args))
    except AttributeError:  # pragma: no cover - another numba layout: numba's own dispatch
        return kernel


def structure(module: str, name: str, fields) -> type:
    """A class whose objects hold values (arrays, numbers) under the names `fields`, given in that order to its
    constructor, for kernels that take them as one argument and read them as attributes: a kernel call unboxes
    each array argument (~0.05 us each), a structure once, holding the same arrays (not copies).

    Compiled: a numba structure (numba.experimental.structref; its numba type the class `name + "Type"`); build
    it in a kernel (a cached call: calling the class from Python would compile its constructor in every
    process). The caller binds the class, and the type as `name + "Type"`, at the top of `module` (numba's
    cache pickles the type by reference). Without numba a plain class with those attributes. A field may not be
    named `st` (the name numba's generated constructor gives the structure it builds)."""
    if _numba is None:
        def __init__(self, *values):
            for field_name, value in zip(fields, values):
                setattr(self, field_name, value)
        return type(name, (), {"__init__": __init__, "__module__": module, "__qualname__": name})

    def preprocess_fields(self, fs):
        return tuple((n, _types.unliteral(t)) for n, t in fs)  # literal values widened to their types

    typ = _structref.register(type(name + "Type", (_types.StructRef,), {
        "preprocess_fields": preprocess_fields, "__module__": module, "__qualname__": name + "Type"}))
    proxy = type(name, (_structref.StructRefProxy,), {"__module__": module, "__qualname__": name})
    _structref.define_proxy(proxy, typ, list(fields))
    proxy.numba_type = typ
    return proxy


def broadcast_call(loop, *args):
    """Array form of a scalar kernel: `loop(a1, ..., ak, out)` is a compiled loop applying the kernel to
    1-D float arrays element by element; the arguments are broadcast against each other (numpy rules) and
    the result has their broadcast shape (a 0-d result comes back as a float)."""
    arrs = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in args])
    shape = arrs[0].shape
    flat = [np.ascontiguousarray(a).reshape(-1) for a in arrs]
    out = np.empty(flat[0].shape[0])
    loop(*flat, out)
    return out.reshape(shape) if shape else float(out[0])
