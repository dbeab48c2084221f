"""examples/foxglove-layout.json (every session) and examples/foxglove-layout-fbg.json (sessions of the FBG sensor
kinds): every panel each holds is placed, every topic it shows is a live channel of its sessions, and only the
FBG layout shows the FBG channel (in an FSR session that panel would stay empty)."""

import json
import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from teleop.loop.live import channels as lc
from teleop.loop.sensor_tap import with_fbg_channel
from teleop.loop.session import PAD_COLORS
from teleop.loop.tap import session_layout

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
LAYOUT = EXAMPLES / "foxglove-layout.json"
LAYOUT_FBG = EXAMPLES / "foxglove-layout-fbg.json"
# each layout with the row layout of the sessions it is for (the FBG one: sensor fbg, every cable an FBG)
ROWS = {LAYOUT: session_layout(), LAYOUT_FBG: with_fbg_channel(session_layout(), SimpleNamespace(kind="fbg", n=6))}
LAYOUTS = pytest.mark.parametrize("path", [LAYOUT, LAYOUT_FBG], ids=["default", "fbg"])


def leaves(node):
    if isinstance(node, str):
        return [node]
    return leaves(node["first"]) + leaves(node["second"])


@LAYOUTS
def test_layout_panels_and_topics(path):
    doc = json.loads(path.read_text())
    assert sorted(leaves(doc["layout"])) == sorted(doc["configById"])
    topics = set(re.findall(r'"(/live/[a-z_]+)', json.dumps(doc["configById"])))
    rows = ROWS[path]
    live = set(lc.rates(rows)) | {lc.TOPIC_FAULTS}
    assert topics <= live and {"/live/scene", "/live/faults", "/live/stylus", "/live/loop"} <= topics
    assert (lc.TOPIC_FBG_LIVE in topics) == (path == LAYOUT_FBG)
    paths = re.findall(r'"(/live/[a-z_]+)\.([a-z_]+)', json.dumps(doc["configById"]))
    assert len(paths) > 20
    plots = lc.plots(rows)
    for topic, name in paths:  # every plotted field is one the channel carries
        assert name in plots[topic][1] or (topic, name) == ("/live/loop", "state_name"), (topic, name)


# panel types Foxglove Studio 1.48 registers (@foxglove/studio-base src/panels/index.js) that the layout uses
STUDIO_PANELS = {"3D", "Plot", "RawMessages", "RosOut", "StateTransitions"}
AXIS_LENGTH = 0.2  # [m] of a frame's axes at axisScale 1 (Studio's renderables/Axis: shaft 0.154 + head 0.046)


@LAYOUTS
def test_layout_opens_in_studio_framed_on_the_robot(path):
    doc = json.loads(path.read_text())
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
