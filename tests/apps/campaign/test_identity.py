"""Task identity and seeding: the streams come from the seed and the identity, never from spawn order."""

import numpy as np

from teleop.apps.campaign.identity import Task, canonical_json, seeds, stream


def test_stream_is_the_spawned_child_at_that_position():
    children = np.random.SeedSequence(7).spawn(5)
    for k in (0, 3, 4):
        assert (stream(7, k).generate_state(4) == children[k].generate_state(4)).all()
    # addressed by identity: the child of participant 4 does not depend on how many were spawned before
    assert seeds(7, 4) == seeds(7, 4) != seeds(7, 3) != seeds(8, 3)


def test_task_id_is_a_digest_of_kind_and_identity_in_any_key_order():
    a = Task("blind-jnd", {"seed": 1, "rig": {"x": 0.1, "y": True}}, "a")
    b = Task("blind-jnd", {"rig": {"y": True, "x": 0.1}, "seed": 1}, "another label")
    assert a.id == b.id and a.id.startswith("blind-jnd-") and len(a.id) == len("blind-jnd-") + 20
    assert Task("blind-jnd", {"seed": 2, "rig": {"x": 0.1, "y": True}}, "a").id != a.id
    assert Task("diagnose", a.identity, "a").id != a.id
    assert canonical_json({"b": 0.1, "a": [1, 2.5]}) == '{"a":[1,2.5],"b":0.1}'
