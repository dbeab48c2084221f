"""Where tasks run: `none` (in this process, one after another), `local:N` (a Dask LocalCluster of N worker
processes, one thread each) or `tcp://HOST:PORT` / `tls://HOST:PORT` (a running Dask scheduler: a cluster
started by hand with `dask scheduler` / `dask worker`, or by dask-jobqueue on SLURM/PBS).

All three run the same function on each task, `guarded`, which times it and turns an exception into a
failed Outcome (so one failing task never sinks the others). Before the tasks, `warm(fn)` runs a kind's
one-off per-process set-up (imports, loading the compiled kernels) once in each worker process, timed apart
from the tasks (a worker that joins later, or one restarted after a crash, warms on its first task).

Tasks run with the BLAS/OpenMP thread pools at one thread (threadpoolctl): Dask's nannies start workers so
(OMP/MKL/OPENBLAS_NUM_THREADS=1), and a threaded BLAS may sum in another order, so the in-process run does
the same for its duration, and a worker process sets it once on its first task (for workers started
without a nanny); a result is the same bytes wherever it ran.

A LocalCluster runs with LOCAL_CONFIG: Dask's defaults wake every process many times a second for things a
batch of long tasks does not use (the statistical profiler samples the task's stack every 10 ms, the event
loop's tick monitor runs every 20 ms, work stealing every 100 ms, memory and system monitors every 0.1-0.5
s), and on a machine with as many workers as cores that CPU is taken from the tasks; LOCAL_CONFIG turns
them down. And the workers keep glibc's own heap trimming: Dask's nannies spawn workers with
MALLOC_TRIM_THRESHOLD_=65536 (to hand freed memory back to the system at once), which costs a blind-jnd
task CPU (its small arrays and pybullet's are returned and faulted in again). A nanny also leaves that
variable in the environment of the process that started it; it is kept out while a LocalCluster starts.
A cluster behind tcp:// keeps its own settings.
"""

from __future__ import annotations

import logging
import os
import re
import socket
import time
import traceback
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator

from threadpoolctl import threadpool_limits

from teleop.core.errors import InputError

TRIM = "MALLOC_TRIM_THRESHOLD_"
LOCAL_CONFIG = {  # see the module docstring; none of these changes which task runs where or its result
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",  # only warns of a blocked event loop
    "distributed.admin.system-monitor.interval": "5s",  # the dashboard's CPU / memory / network figures
    "distributed.worker.memory.monitor-interval": "1s",  # memory limits still enforced, checked each second
    "distributed.scheduler.work-stealing": False,  # tasks wait on the scheduler until a worker is free
}
FORMS = "none, local:N (N worker processes) or tcp://HOST:PORT (a running Dask scheduler)"
WARM_TIMEOUT_S = 600.0  # the workers' set-up (a stale kernel cache compiles: about a minute here)
WINDOW = 1000  # tasks submitted ahead of their results (bounds the client's and the scheduler's memory)


@dataclass(frozen=True)
class Outcome:
    """What became of one task: its value, or the error (one line) and traceback text; `seconds` and
    `cpu_seconds` are the task's own wall and CPU time (its process's, all threads) where it ran (0 when it
    never ran, e.g. its worker died), `thread_cpu_seconds` the CPU time of the thread that ran it alone
    (the rest of `cpu_seconds` is the worker's own threads meanwhile: event loop, heartbeats); `worker`
    ("host:pid") and `started` / `ended` (Unix time [s]) say where and when it ran. On a machine shared
    with other work the wall time grows with the load, the CPU time hardly: it is what a dedicated core
    would take."""

    ok: bool
    value: object = None
    error: str = ""
    traceback: str = ""
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    thread_cpu_seconds: float = 0.0
    worker: str = ""
    started: float = 0.0
    ended: float = 0.0


_COLOUR = re.compile(r"\x1b\[[0-9;]*m")  # terminal colour codes


def error_line(exc: BaseException) -> str:
    """`Type: message` on one line, terminal colour codes (numba's) removed."""
    text = _COLOUR.sub("", str(exc))
    return f"{type(exc).__name__}: {' '.join(text.split())}"



def _where() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def guarded(fn: Callable, item) -> Outcome:
    """fn(item) as an Outcome, timed."""
    started, t0, c0, h0 = time.time(), time.perf_counter(), time.process_time(), time.thread_time()

    def timing() -> dict:
        return {"seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0,
                "thread_cpu_seconds": time.thread_time() - h0, "worker": _where(), "started": started,
                "ended": time.time()}

    try:
        value = fn(item)
    except Exception as exc:  # noqa: BLE001 - any task failure is reported, never raised into the others
        return Outcome(False, error=error_line(exc), traceback=traceback.format_exc(), **timing())
    return Outcome(True, value=value, **timing())


def timed_warm(fn: Callable) -> float:
    """fn() (a kind's per-process set-up) in this process; its wall time [s]."""
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


_WORKER_POOLS = []  # holds the limiter of this worker process once set (never restored: a worker only runs tasks)


def guarded_on_worker(fn: Callable, item) -> Outcome:
    """`guarded` in a Dask worker: the BLAS/OpenMP pools of this process at one thread from its first task."""
    if not _WORKER_POOLS:
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

    def warm(self, fn: Callable) -> list:
        """[seconds] of fn() run once here."""
        return [timed_warm(fn)]

    def run(self, fn: Callable, items: Iterable) -> Iterator[tuple]:
        """(item, Outcome) for each item, as each finishes, the BLAS/OpenMP pools at one thread meanwhile."""
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
        import dask  # heavy: loaded only to run on Dask
        from distributed import Client, LocalCluster  # heavy: loaded only to run on Dask

        if self.address is None:
            try:
                environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ").items()
                           if k != TRIM}  # the thread limits (OMP/MKL/OPENBLAS_NUM_THREADS=1) stay
                kept = os.environ.pop(TRIM, None)
                try:
                    with dask.config.set({**LOCAL_CONFIG, "distributed.nanny.pre-spawn-environ": environ}):
                        self.cluster = LocalCluster(n_workers=self.n_workers, threads_per_worker=1,
                                                    processes=True, dashboard_address=None,
                                                    silence_logs=logging.ERROR)
                finally:
                    if kept is not None:
                        os.environ[TRIM] = kept
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

    def warm(self, fn: Callable) -> list:
        """[seconds] of fn() on each worker process the scheduler knows now (one task pinned to each, all
        at once). A worker that fails it, or dies under it (its pinned task would wait for it for ever: a
        restarted worker has another address), is left to warm on its first task; at most WARM_TIMEOUT_S."""
        futs = [self.client.submit(timed_warm, fn, workers=[w], allow_other_workers=False, pure=False)
                for w in self.client.nthreads()]
        deadline, out = time.monotonic() + WARM_TIMEOUT_S, []
        for f in futs:
            try:
                out.append(f.result(timeout=max(0.0, deadline - time.monotonic())))
            except Exception:  # noqa: BLE001 - a failed or stuck set-up is left to the first task
                pass
        self.client.cancel(futs)
        return out

    def run(self, fn: Callable, items: Iterable) -> Iterator[tuple]:
        """(item, Outcome) for each item, in the order they finish. A worker that dies under a task (Dask
        retries it elsewhere first) or any other scheduling error is that task's failed Outcome."""
        from distributed import as_completed  # heavy: loaded only to run on Dask

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
