"""Every pad of the scene, indented in pybullet, has the slope its material predicts (within 5 %)."""

import numpy as np
import pytest

from scenes.calibration import indent, slope
from scenes.pads import (BLIND_MATERIALS, all_pads, blind_area_centres, blind_test_order, blind_test_pad, hole_pad,
                         letter_mask, scan_grid, three_region_pad, z_test_pad)
from scenes.world import PadWorld, WorldParams
from teleop.core.errors import InputError

PARAMS = WorldParams()


@pytest.mark.parametrize("pad", all_pads(), ids=lambda p: p.name)
def test_every_pad_region_slope_within_5_percent(pad):
    with PadWorld(pad, PARAMS) as w:
        if pad.hole_radius > 0:
            for axis in (0, 1):
                d, F = indent(w, (0.0, 0.0), axis=axis)
                assert slope(d, F) == pytest.approx(pad.wall_stiffness(PARAMS.tip_radius), rel=0.05)
            return
        probes = pad.probe_points(PARAMS.tip_radius)
        assert len(probes) == len({r.label or r.material for r in pad.regions}) + 1
        for label, xy in probes.items():
            d, F = indent(w, xy)
            target = pad.stiffness_at(np.asarray(xy), PARAMS.tip_radius)
            assert slope(d, F) == pytest.approx(target, rel=0.05), label


@pytest.mark.parametrize("pad", [three_region_pad(), hole_pad()], ids=lambda p: p.name)
def test_slopes_hold_at_the_palpation_time_step(pad):
    """The palpation protocols step pybullet at 500 Hz: the calibration is re-measured there."""
    params = WorldParams(dt=2e-3, surface_z=0.0235)
    with PadWorld(pad, params) as w:
        if pad.hole_radius > 0:
            d, F = indent(w, (0.0, 0.0), axis=1)
            assert slope(d, F) == pytest.approx(pad.wall_stiffness(params.tip_radius), rel=0.05)
            return
        for label, xy in pad.probe_points(params.tip_radius).items():
            d, F = indent(w, xy)
            assert slope(d, F) == pytest.approx(pad.stiffness_at(np.asarray(xy), params.tip_radius), rel=0.05), label


def test_three_region_pad_order_of_table_1():
    pad = three_region_pad()
    k = {lab: pad.stiffness_at(np.asarray(xy), PARAMS.tip_radius) for lab, xy in pad.points.items()}
    assert k["red"] > k["yellow"] > k["black"]


def test_z_pad_has_25_points_on_three_circles():
    pts = np.array(list(z_test_pad().points.values()))
    assert len(pts) == 25
    r = np.round(np.hypot(pts[:, 0], pts[:, 1]) * 2e3, 6)
    assert sorted(set(r)) == [0.0, 8.0, 16.0, 24.0]


def test_letters_on_6x7_grid_and_distinct():
    assert scan_grid().shape == (7, 6, 2)
    e, p = letter_mask("E"), letter_mask("P")
    assert e.shape == (7, 6) and (e != p).any() and e.sum() > 10 and p.sum() > 10


def test_blind_pad_rearranged_by_seed():
    orders = {blind_test_order(s) for s in range(20)}
    assert len(orders) > 5
    assert all(sorted(o) == sorted(BLIND_MATERIALS) for o in orders)
    pad = blind_test_pad(blind_test_order(3))
    for i, c in enumerate(blind_area_centres()):
        assert pad.layer_at(c[None])[0][0] == blind_test_order(3)[i]
    with pytest.raises(InputError):
        blind_test_pad(("pla", "pla", "pla", "pla"))


def test_hole_pad_hole_is_free():
    pad = hole_pad()
    with PadWorld(pad, PARAMS) as w:
        z = PARAMS.surface_z + 0.003
        for _ in range(100):
            w.step([0.0, 0.0, z])
        assert np.allclose(w.contact_force(), 0.0)
