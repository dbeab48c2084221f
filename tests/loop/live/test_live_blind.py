"""`teleop blind-test --operator human --live`: the experimenter's screen over Foxglove's protocol shows the
trial (zones, slots, the pad under each slot), every answer and the ratings, and the pad scene."""

import asyncio
import json
import re
import subprocess
import sys

from teleop.loop.live import study
from tests.loop.live._client import receive_until_closed, subscribe_all

P1 = ["h", "s", "h", "r", "h", "s", "h", "10 7 4 2"]  # the answers of tests/apps/protocols/test_blind_human.py's P1


def test_experimenter_screen(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "teleop.apps.cli", "blind-test", "--operator", "human", "--haptic",
                             "none", "--participants", "1", "--seed", "7", "--state", str(tmp_path / "s.json"),
                             "--live", "0"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    for line in proc.stdout:
        m = re.search(r"live view: ws://127\.0\.0\.1:(\d+)", line)
        if m:
            break
    else:
        raise AssertionError(proc.stderr.read())

    async def watch():
        ws, subs = await subscribe_all(int(m.group(1)))
        await asyncio.sleep(0.3)
        proc.stdin.write("\n".join(P1) + "\n")
        proc.stdin.close()
        return subs, await receive_until_closed(ws)
    subs, frames = asyncio.run(watch())
    proc.stdout.read()
    assert proc.wait(60) == 0, proc.stderr.read()
    got = {}
    for sid, _, payload in frames:
        got.setdefault(subs[sid]["topic"], []).append(payload)
    trials = [json.loads(p) for p in got[study.TOPIC_TRIAL]]
    compare = [t for t in trials if t["kind"] == "compare"]  # a late subscriber got the current trial again
    assert compare and set(compare[0]["pads"]) == set("ABCD") and compare[0]["new_zone"] != compare[0]["ref_zone"]
    assert [t["answer"] for t in trials if t["kind"] == "answer"] == ["harder", "softer", "harder", "unsure",
                                                                      "harder", "softer", "harder"]
    assert trials[-1]["kind"] == "ratings" and trials[-1]["ratings"] == [10, 7, 4, 2]
    logs = got[study.TOPIC_ANSWERS]
    assert len(logs) == 8 and b"ratings [10, 7, 4, 2]" in logs[-1]
    assert len(got[study.TOPIC_SCENE]) >= len(trials) and all(b"slot/A" in p for p in got[study.TOPIC_SCENE])
