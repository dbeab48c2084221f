"""Where the tests find real data: a `shared/data` folder beside the checkout (the development layout; absent in a
plain clone, where the tests that need it skip) and the excerpts that ship in examples/."""

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
MRDLAB = REPO.parent / "shared" / "data" / "mrdlab"          # the six MRDLab runs, ODbL 1.0
EXAMPLE_MRDLAB = REPO / "examples" / "mrdlab"                # the first 8 s of one run, in the repository
needs_mrdlab = pytest.mark.skipif(not MRDLAB.is_dir(), reason="the full MRDLab runs are absent")
