"""examples/foxglove-layout.json: every panel it holds is placed, and every topic it shows is a live channel."""

import json
import re
from pathlib import Path

from teleop.loop.live import channels as lc
from teleop.loop.session import PAD_COLORS

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


# panel types Foxglove Studio 1.48 registers (@foxglove/studio-base src/panels/index.js) that the layout uses
STUDIO_PANELS = {"3D", "Plot", "RawMessages", "RosOut", "StateTransitions"}
AXIS_LENGTH = 0.2  # [m] of a frame's axes at axisScale 1 (Studio's renderables/Axis: shaft 0.154 + head 0.046)


def test_layout_opens_in_studio_framed_on_the_robot():
    doc = json.loads(LAYOUT.read_text())
    conf = doc["configById"]
    assert {k.split("!")[0] for k in conf} <= STUDIO_PANELS  # "Log" is "Unknown panel type" in Studio
    assert conf["RosOut!faults"]["topicToRender"] == lc.TOPIC_FAULTS
    three = conf["3D!scene"]
    cam = three["cameraState"]
    assert cam["near"] <= 0.002 and cam["far"] >= 1.0  # Studio's default near plane (0.5 m) clips the robot
    axes = three["scene"]["transforms"]
    assert AXIS_LENGTH * axes["axisScale"] <= 2 * lc.EE_DIAMETER  # axes the size of the end effector
    assert axes["labelSize"] <= lc.EE_DIAMETER
    # the camera on the workspace: the base ring (20 mm), the tool and the pad (z 30..36 mm) fill the view
    assert 0.05 <= cam["distance"] <= 0.3 and max(abs(v) for v in cam["targetOffset"]) <= 0.03
    assert three["followTf"] == "world" and all(three["topics"][t]["visible"] for t in (lc.TOPIC_SCENE, lc.TOPIC_TF))
    for key, panel in conf.items():
        if key.startswith("Plot!"):  # the legend beside the chart, never floating over the data
            assert panel["legendDisplay"] in ("top", "left", "none") or not panel["showLegend"], key
    assert {conf["RawMessages!timing"]["topicPath"], conf["RawMessages!stats"]["topicPath"]} == \
        {lc.TOPIC_TIMING, lc.TOPIC_STATS}


def test_scene_colours_tell_the_end_effector_apart():
    others = {lc.CABLE_COLOR, lc.FORCE_COLOR, lc.EE_FAULT_COLOR}
    assert lc.EE_COLOR not in others
    for c in (*others, *PAD_COLORS):  # far from every other colour in the scene (RGB distance)
        assert sum((a - b) ** 2 for a, b in zip(lc.EE_COLOR[:3], c[:3])) ** 0.5 > 0.4, c
