"""examples/foxglove-layout.json: every panel it holds is placed, and every topic it shows is a live channel."""

import json
import re
from pathlib import Path

from teleop.loop.live import channels as lc

LAYOUT = Path(__file__).resolve().parents[3] / "examples" / "foxglove-layout.json"


def leaves(node):
    if isinstance(node, str):
        return [node]
    return leaves(node["first"]) + leaves(node["second"])


def test_layout_panels_and_topics():
    doc = json.loads(LAYOUT.read_text())
    assert sorted(leaves(doc["layout"])) == sorted(doc["configById"])
    topics = set(re.findall(r'"(/live/[a-z_]+)', json.dumps(doc["configById"])))
    live = set(lc.RATES) | {lc.TOPIC_FAULTS}
    assert topics <= live and {"/live/scene", "/live/faults", "/live/stylus", "/live/loop"} <= topics
    paths = re.findall(r'"(/live/[a-z_]+)\.([a-z_]+)', json.dumps(doc["configById"]))
    assert len(paths) > 20
    for topic, name in paths:  # every plotted field is one the channel carries
        assert name in lc.PLOTS[topic][1] or (topic, name) == ("/live/loop", "state_name"), (topic, name)
