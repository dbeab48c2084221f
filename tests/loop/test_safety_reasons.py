"""Fault reasons print the digits that make them true: a telemetry age of 20.04 ms over a 20 ms limit reads
"20.04 ms > 20 ms" (it read "20.0 ms > 20.0 ms"), whatever the margin."""

import re

import numpy as np
import pytest

from teleop.loop.safety import Freshness, TensionRange, beyond


def comparison_holds(text: str) -> bool:
    m = re.search(r"(-?[\d.]+) (\w+) ([<>]) (-?[\d.e+-]+) \2", text)
    assert m, text
    a, op, b = float(m.group(1)), m.group(3), float(m.group(4))
    return a > b if op == ">" else a < b


@pytest.mark.parametrize("value,limit", [(20.04, 20.0), (20.0004, 20.0), (26.0, 20.0), (12.5000001, 12.5),
                                         (0.0200001, 0.02), (1e3 * 0.0201, 1e3 * 0.02)])
def test_beyond_shows_a_true_comparison(value, limit):
    text = beyond(value, limit, "ms")
    assert comparison_holds(text) and text.endswith(f"> {limit:g} ms")
    assert comparison_holds(beyond(limit - (value - limit), limit, "N", "<"))


def test_stale_telemetry_reason():
    f = Freshness("robot", 0.020)
    f.reset(0.0)
    f.update(1.0, key=1)
    assert f.check(1.0199999) is None
    assert comparison_holds(f.check(1.020))  # 1.020 - 1.0 is 20.000000000000018 ms in floats: shown so
    reason = f.check(1.02004)
    assert reason == "robot telemetry stale: 20.04 ms > 20 ms"
    assert comparison_holds(f.check(1.0200001))
    g = Freshness("stylus", 0.020, startup=0.5)
    g.reset(0.0)
    assert comparison_holds(g.check(0.5000004)) and "missing for 500.0004 ms > 500 ms" in g.check(0.5000004)


def test_tension_reason():
    rng = TensionRange(t_max=12.0, t_slack=0.5, window=0.010)
    t = np.full(6, 3.0)
    t[2] = 12.0004
    assert rng.update(0.0, t) is None
    reason = rng.update(0.0101, t)
    assert reason.startswith("cable 3 tension over-range for 10.1 ms > 10 ms (12.0004 N > 12 N)"), reason
