"""LoopParams holds the rendering settings (RenderParams): one home for force scale, -z zeroing, ramp-in and the
engage test; older keyword names and recorded configurations still construct it."""

import json

import numpy as np
import pytest

from teleop.core.errors import InputError
from teleop.loop.params import LOOP_RENDER, LoopParams
from teleop.loop.replay import params_from
from teleop.core.mapping import MappingParams
from teleop.core.rendering import RenderParams


def test_older_keywords_set_the_render_settings_and_read_back():
    p = LoopParams(force_scale=0.5, zero_neg_z=True, ramp_time=0.1, engage_force=0.3, engage_ticks=5)
    r = p.render
    assert (r.scale, r.zero_negative_z, r.ramp_s, r.engage_N, r.engage_ticks) == (0.5, True, 0.1, 0.3, 5)
    assert (p.force_scale, p.zero_neg_z, p.ramp_time, p.engage_force, p.engage_ticks) == (0.5, True, 0.1, 0.3, 5)
    assert LoopParams().render.ramp_s == LOOP_RENDER.ramp_s and LoopParams().force_scale == 1.0


def test_force_frame_is_the_motion_registration_transposed():
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    p = LoopParams(mapping=MappingParams(R_reg=R), render=RenderParams(R_dev_B=np.eye(3)))
    np.testing.assert_array_equal(np.array(p.render.R_dev_B), R.T)


def test_recorded_configuration_round_trips_new_and_old_layouts():
    p = LoopParams(rate_hz=500.0, force_scale=0.25, zero_neg_z=True,
                   mapping=MappingParams(motion_scale=0.5))
    q = params_from(json.loads(json.dumps(p.as_dict())))
    assert q.render == p.render and q.rate_hz == 500.0 and q.mapping.motion_scale == 0.5
    old = json.loads(json.dumps(p.as_dict()))
    del old["render"]
    old.update(force_scale=0.25, zero_neg_z=True, ramp_time=0.25, engage_force=0.2, engage_ticks=3)
    assert params_from(old).render == p.render


@pytest.mark.parametrize("kw", [{"force_scale": 0.0}, {"engage_force": 0.0}, {"engage_ticks": 0},
                                {"ramp_time": -1.0}, {"render": {"scale": 1.0, "bogus": 2}}])
def test_bad_render_settings_are_input_errors(kw):
    with pytest.raises(InputError, match="loop|render"):
        LoopParams(**kw)
