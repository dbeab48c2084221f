"""devices.guard.guarded_force: the one force guard of every stylus backend."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from devices.base import OMEGA_SPEC, TOUCH_SPEC, DeviceError
from devices.guard import guarded_force

wild = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([1e308, -1e308, 0.5, -0.5]))


@settings(derandomize=True, max_examples=150, deadline=None)
@given(f=st.lists(wild, min_size=3, max_size=3), spec=st.sampled_from([TOUCH_SPEC, OMEGA_SPEC]))
def test_any_force_becomes_finite_within_peak_direction_kept(f, spec):
    dev = SimpleNamespace(is_open=True, spec=spec)
    out = guarded_force(dev, f, "dev")
    assert all(math.isfinite(c) for c in out)
    assert math.hypot(*out) <= spec.max_force_peak * (1 + 1e-12)
    if not all(math.isfinite(c) for c in f):
        assert out == (0.0, 0.0, 0.0)
    elif math.hypot(*out) > 0:
        assert np.allclose(np.cross(out, np.array(f) / max(map(abs, f))), 0.0, atol=1e-9)
        if np.linalg.norm(np.array(f) / max(map(abs, f))) * max(map(abs, f)) <= spec.max_force_peak:
            assert out == tuple(f)


def test_closed_device_and_wrong_shape_are_device_errors():
    with pytest.raises(DeviceError, match="dev: servo_cf\\(\\) before open"):
        guarded_force(SimpleNamespace(is_open=False, spec=TOUCH_SPEC), [0, 0, 0], "dev")
    with pytest.raises(DeviceError, match="dev: force must have 3 components"):
        guarded_force(SimpleNamespace(is_open=True, spec=TOUCH_SPEC), [0, 0], "dev")
