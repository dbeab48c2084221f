"""Fill numba's on-disk cache before a full run of the suite (tests/conftest.py starts this twice, one process
per part, while pytest-xdist's workers start and collect): `python -m tests._warm_kernels loop|diagnosis`.

On a cold cache (a fresh clone, or any kernel source changed: the caches are stamped with all of them) every
process that calls a kernel first compiles it: both workers, each `teleop` child process and each Dask worker
a test starts before another process has written the kernel to the cache. Compiled here once, on both cores
at once, they are loaded by all of those. A warm cache: nothing is compiled, the process ends at once.

- loop: `teleop.loop.warm.warm_up`, every kernel of the loop and the simulated robot (as `teleop warm`), its
  first group (the loop's own kernels) left to the other part: the groups after it first, then `warm_up`,
  which finds the first group's kernels in the cache and records the complete warm-up.
- diagnosis: the loop's own kernels (warm_up's first group), then `teleop.diagnosis.diagnose` on a short
  generated rig recording: the effects' and links' kernels. The two parts take about as long.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

from teleop.core.geometry import default_geometry
from teleop.diagnosis.diagnose import diagnose
from teleop.diagnosis.generator import GenConfig, make_case
from teleop.io.recording_io import read_interchange
from teleop.loop.warm import GROUPS, cache_is_cold, warm_up

PARTS = ("loop", "diagnosis")


def warm_diagnosis() -> None:
    """Diagnose a 5 s rig recording with a backlash (seeded): every candidate effect is fitted on its link."""
    with tempfile.TemporaryDirectory() as d:
        csv = make_case(0, "backlash", "rig", seed=0, cfg=GenConfig(duration_s=5.0)).write(Path(d) / "c.csv")
        diagnose(read_interchange(csv))


def warm_groups(groups) -> None:
    """Run warm_up's `groups` [(name, function)] in order on the default geometry, as warm_up does."""
    geom = default_geometry()
    state = SimpleNamespace(geom=geom, n=len(geom.B))
    for _, group in groups:
        group(state)


def main(part: str) -> int:
    if part not in PARTS:
        print(f"tests._warm_kernels: expected one of {', '.join(PARTS)}, got {part!r}", file=sys.stderr)
        return 2
    if not cache_is_cold():  # the last complete warm-up's kernels are all in the cache for these sources
        return 0
    if part == "loop":
        warm_groups(GROUPS[1:])
        warm_up(say=None)
    else:
        warm_groups(GROUPS[:1])
        warm_diagnosis()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else ""))
