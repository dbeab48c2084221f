"""Where tasks run: `none` (in this process, one after another), `local:N` (a Dask LocalCluster of N worker
processes, one thread each) or `tcp://HOST:PORT` / `tls://HOST:PORT` (a running Dask scheduler: a cluster
started by hand with `dask scheduler` / `dask worker`, or by dask-jobqueue on SLURM/PBS).

All three run the same function on each task, `guarded`, which times it and turns an exception into a
failed Outcome (so one failing task never sinks the others). Tasks run with the BLAS/OpenMP thread pools at
one thread (threadpoolctl): Dask's nannies start workers so (OMP/MKL/OPENBLAS_NUM_THREADS=1), and a threaded
BLAS may sum in another order, so the in-process run does the same for its duration, and a worker process
sets it once on its first task (for workers started without a nanny); a result is the same bytes wherever
it ran.
"""

from __future__ import annotations

import re
import time
import traceback
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator

from teleop.errors import InputError

FORMS = "none, local:N (N worker processes) or tcp://HOST:PORT (a running Dask scheduler)"
WINDOW = 1000  # tasks submitted ahead of their results (bounds the client's and the scheduler's memory)


@dataclass(frozen=True)
class Outcome:
    """What became of one task: its value, or the error (one line) and traceback text; `seconds` and
    `cpu_seconds` are the task's own wall and CPU time (its process's, all threads) where it ran (0 when it
    never ran, e.g. its worker died). On a machine shared with other work the wall time grows with the
    load, the CPU time hardly: it is what a dedicated core would take."""

    ok: bool
    value: object = None
    error: str = ""
    traceback: str = ""
    seconds: float = 0.0
    cpu_seconds: float = 0.0


_COLOUR = re.compile(r"\x1b\[[0-9;]*m")  # terminal colour codes


def error_line(exc: BaseException) -> str:
    """`Type: message` on one line, terminal colour codes (numba's) removed."""
    text = _COLOUR.sub("", str(exc))
    return f"{type(exc).__name__}: {' '.join(text.split())}"



def guarded(fn: Callable, item) -> Outcome:
    """fn(item) as an Outcome, timed."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        value = fn(item)
    except Exception as exc:  # noqa: BLE001 - any task failure is reported, never raised into the others
        return Outcome(False, error=error_line(exc), traceback=traceback.format_exc(),
                       seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - c0)
    return Outcome(True, value=value, seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - c0)


_WORKER_POOLS = []  # holds the limiter of this worker process once set (never restored: a worker only runs tasks)


def guarded_on_worker(fn: Callable, item) -> Outcome:
    """`guarded` in a Dask worker: the BLAS/OpenMP pools of this process at one thread from its first task."""
    if not _WORKER_POOLS:
        from threadpoolctl import threadpool_limits

        _WORKER_POOLS.append(threadpool_limits(limits=1))
    return guarded(fn, item)


def parse_scheduler(text: str) -> tuple:
    """'none' -> ("none", None); 'local:N' -> ("local", N); 'tcp://h:p' -> ("address", 'tcp://h:p')."""
    s = str(text).strip()
    if s == "none":
        return "none", None
    m = re.fullmatch(r"local:(\d+)", s)
    if m and int(m.group(1)) >= 1:
        return "local", int(m.group(1))
    if re.fullmatch(r"(tcp|tls)://[^\s/:]+:\d+", s):
        return "address", s
    raise InputError(f"--scheduler '{text}': expected {FORMS}")


class InProcess:
    """Tasks one after another in this process (the reference every other scheduler must match)."""

    name = "none"
    workers = 1

    def __enter__(self) -> "InProcess":
        return self

    def __exit__(self, *exc) -> None:
        pass

    def run(self, fn: Callable, items: Iterable) -> Iterator[tuple]:
        """(item, Outcome) for each item, as each finishes, the BLAS/OpenMP pools at one thread meanwhile."""
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1):
            for item in items:
                yield item, guarded(fn, item)


class DaskScheduler:
    """Tasks on Dask workers: a LocalCluster of `n_workers` processes started here, or the scheduler at
    `address`. Results come back as each task finishes (`as_completed`); at most WINDOW are in flight."""

    def __init__(self, n_workers: int | None = None, address: str | None = None):
        self.n_workers, self.address = n_workers, address
        self.name = address or f"local:{n_workers}"
        self.cluster = self.client = None

    def __enter__(self) -> "DaskScheduler":
        import logging

        from distributed import Client, LocalCluster

        if self.address is None:
            try:
                self.cluster = LocalCluster(n_workers=self.n_workers, threads_per_worker=1, processes=True,
                                            dashboard_address=None, silence_logs=logging.ERROR)
            except Exception as exc:  # noqa: BLE001 - no workers (memory, a broken install): say so in a line
                raise InputError(f"--scheduler {self.name}: the Dask LocalCluster did not start "
                                 f"({type(exc).__name__}: {exc})") from None
            self.client = Client(self.cluster, set_as_default=False)
        else:
            try:
                self.client = Client(self.address, timeout="20s", set_as_default=False)
            except (OSError, TimeoutError) as exc:
                raise InputError(f"--scheduler {self.address}: no Dask scheduler answered ({exc})") from None
        return self

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        self.client = self.cluster = None

    @property
    def workers(self) -> int:
        """Worker threads the scheduler knows now."""
        return sum(self.client.nthreads().values()) if self.client is not None else 0

    def run(self, fn: Callable, items: Iterable) -> Iterator[tuple]:
        """(item, Outcome) for each item, in the order they finish. A worker that dies under a task (Dask
        retries it elsewhere first) or any other scheduling error is that task's failed Outcome."""
        from distributed import as_completed

        items = iter(items)
        pending = {}
        done = as_completed(loop=self.client.loop)  # this client's loop, not a process-wide default client

        def submit() -> bool:
            item = next(items, _END)
            if item is _END:
                return False
            fut = self.client.submit(guarded_on_worker, fn, item, pure=False)
            pending[fut] = item
            done.add(fut)
            return True

        for _ in range(WINDOW):
            if not submit():
                break
        for fut in done:
            item = pending.pop(fut)
            try:
                outcome = fut.result()
            except Exception as exc:  # noqa: BLE001 - KilledWorker, CancelledError, ...: this task failed
                outcome = Outcome(False, error=error_line(exc))
            fut.release()
            yield item, outcome
            submit()


_END = object()


def open_scheduler(text: str):
    """The scheduler `text` names (see parse_scheduler), as a context manager."""
    kind, arg = parse_scheduler(text)
    if kind == "none":
        return InProcess()
    if kind == "local":
        return DaskScheduler(n_workers=arg)
    return DaskScheduler(address=arg)
