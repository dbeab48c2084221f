"""`teleop warm`: compile (first run) or load (later runs) every kernel of the loop and the simulated robot,
so that the first session or study starts at once; a line per group of kernels with its time."""

from __future__ import annotations

from teleop.loop.warm import COLD_MESSAGE, cache_is_cold, warm_up


def register(subparsers) -> None:
    p = subparsers.add_parser("warm", help="compile or load the compiled kernels now (the first run compiles them)")
    p.set_defaults(func=run)


def run(args) -> int:
    cold = cache_is_cold()
    print(COLD_MESSAGE if cold else "loading compiled kernels ...", flush=True)

    def report(name: str, seconds: float) -> None:
        print(f"  {name}: {seconds:.1f} s", flush=True)
    total = warm_up(say=None, on_group=report)
    print(f"kernels {'compiled' if cold else 'loaded'} in {total:.1f} s; numba's cache now holds them", flush=True)
    return 0
