"""Geometry: defaults follow the seed, TOML round trip, malformed files give one-line errors."""

import numpy as np
import pytest

from teleop.core.errors import InputError
from teleop.core.geometry import default_geometry, load_geometry

GOOD = """
[geometry]
base_anchors_mm = [[20, 0, 0], [10, 17.320508075688775, 0], [-10, 17.320508075688775, 0],
                   [-20, 0, 0], [-10, -17.320508075688775, 0], [10, -17.320508075688775, 0]]
platform_anchors_mm = [[0, 0, -15], [0, 0, 15], [0, 0, -15], [0, 0, 15], [0, 0, -15], [0, 0, 15]]
theta0_deg = 140
mu = 0.056
"""


def test_default_geometry_matches_the_seed():
    g = default_geometry()
    assert np.rad2deg(g.theta0) == pytest.approx(140.0)
    assert g.base_radius == pytest.approx(0.020)
    np.testing.assert_allclose(g.v, [0, 0, 1], atol=1e-12)
    # rear anchors behind the ring plane pull +z, front anchors pull -z
    assert (g.r[::2, 2] < 0).all() and (g.r[1::2, 2] > 0).all()


def test_toml_round_trip(tmp_path):
    p = tmp_path / "g.toml"
    p.write_text(GOOD)
    g = load_geometry(p)
    d = default_geometry()
    np.testing.assert_allclose(g.B, d.B, atol=1e-12)
    np.testing.assert_allclose(g.r, d.r, atol=1e-12)
    assert g.mu == d.mu


@pytest.mark.parametrize("text, needle", [
    ("[geometry]\nmu = 0.1\n", "base_anchors_mm"),
    (GOOD + "colour = 'red'\n", "unknown key 'colour'"),
    (GOOD.replace("mu = 0.056", "mu = 'high'"), "'mu' must be a finite number"),
    (GOOD.replace("[20, 0, 0], [10", "[20, 0, 5], [10"), "one circle in one plane"),
    (GOOD.replace("[0, 0, -15], [0, 0, 15], [0, 0, -15]", "[0, 0, -15], [0, 0, 15]"), "6 vectors"),
    ("[geometry\n", "invalid TOML"),
])
def test_malformed_geometry_names_file_and_key(tmp_path, text, needle):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(InputError) as err:
        load_geometry(p)
    msg = str(err.value)
    assert str(p) in msg and needle in msg and "\n" not in msg
