"""`teleop blind-test --operator human` end to end through a pipe: prompts answered by a script, bad answers
refused, a SIGKILL in the middle, and a resume that loses nothing."""

import json
import os
import select
import signal
import subprocess
import sys
import time

import pytest

P1 = ["h", "s", "x", "h", "r", "h", "s", "h", "11 7 4 2", "10 7 4 2"]   # 'x' and '11 ...' are refused
P2 = ["s", "s", "maybe", "s", "h", "h", "h", "5 5 5 5", "9 6 4 1"]      # 'maybe' and '5 5 5 5' refused
ANSWERS = P1 + P2
PROMPT_ENDS = ("poke both again] ", "decreasing: ")


def command(state, out_json, *extra):
    return [sys.executable, "-m", "teleop.apps.cli", "blind-test", "--operator", "human", "--haptic", "none",
            "--participants", "2", "--seed", "7", "--state", str(state), "--json", str(out_json), *extra]


def read_until_prompts(proc, count, buf, timeout=30.0):
    """Read stdout until `count` prompts have been shown in total; returns the text so far."""
    fd = proc.stdout.fileno()
    end = time.monotonic() + timeout
    while sum(buf.count(p) for p in PROMPT_ENDS) < count:
        r, _, _ = select.select([fd], [], [], max(0.0, end - time.monotonic()))
        if not r:
            raise AssertionError(f"no prompt within {timeout} s; output so far:\n{buf}")
        chunk = os.read(fd, 65536).decode()
        if not chunk:
            raise AssertionError(f"process ended early:\n{buf}")
        buf += chunk
    return buf


def answer_then_kill(state, out, k, wait_next_prompt=False):
    """Run the study, answer its first k prompts one by one (each after its prompt shows), optionally wait
    for the next prompt (everything before it saved), then SIGKILL it."""
    proc = subprocess.Popen(command(state, out), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL)
    buf = ""
    try:
        for i in range(k):
            buf = read_until_prompts(proc, i + 1, buf)
            proc.stdin.write((ANSWERS[i] + "\n").encode())
            proc.stdin.flush()
        if wait_next_prompt:
            read_until_prompts(proc, k + 1, buf)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)


def test_uninterrupted_and_killed_resumed_studies_give_the_same_results(tmp_path):
    # reference: every answer through a pipe in one go
    ref_state, ref_json = tmp_path / "ref_state.json", tmp_path / "ref.json"
    r = subprocess.run(command(ref_state, ref_json), input="\n".join(ANSWERS) + "\n", capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "'x' is not an answer" in r.stdout and "'maybe' is not an answer" in r.stdout
    assert "refused: ratings" in r.stdout and r.stdout.count("refused") == 2
    ref = json.loads(ref_json.read_text())
    assert [p["ratings"] for p in ref["participants"]] == [
        dict(zip(ref["true_order"], [ref["participants"][0]["ratings"][a] for a in ref["true_order"]])),
        dict(zip(ref["true_order"], [ref["participants"][1]["ratings"][a] for a in ref["true_order"]]))]
    assert sorted(ref["participants"][0]["ratings"].values()) == [2, 4, 7, 10]
    assert sorted(ref["participants"][1]["ratings"].values()) == [1, 4, 6, 9]

    # interrupted: answer prompt by prompt, SIGKILL once participant 2 has given two answers
    state, out = tmp_path / "state.json", tmp_path / "out.json"
    n_before = len(P1) + 2
    answer_then_kill(state, out, n_before, wait_next_prompt=True)  # the next prompt: everything before is saved
    saved = json.loads(state.read_text())
    assert saved["records"][0]["ratings"] == [10, 7, 4, 2]
    assert [a[2] for a in saved["records"][1]["answers"]] == ["softer", "softer"]
    assert not out.exists()

    # resume: only the remaining answers are given
    rest = ANSWERS[n_before:]
    r = subprocess.run(command(state, out), input="\n".join(rest) + "\n", capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    assert "Resuming" in r.stdout and "1 of 2 participants done" in r.stdout
    assert out.read_bytes() == ref_json.read_bytes()
    assert json.loads(state.read_text()) == json.loads(ref_state.read_text())


def test_input_ending_early_saves_and_says_how_to_resume(tmp_path):
    state, out = tmp_path / "s.json", tmp_path / "o.json"
    r = subprocess.run(command(state, out), input="h\ns\n", capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert "run the same command again to resume" in r.stdout
    assert len(json.loads(state.read_text())["records"][0]["answers"]) == 2 and not out.exists()


def test_state_of_another_study_is_refused_with_one_line(tmp_path):
    state, out = tmp_path / "s.json", tmp_path / "o.json"
    subprocess.run(command(state, out), input="h\n", capture_output=True, text=True, timeout=60)
    r = subprocess.run(command(state, out, "--seed", "8"), input="h\n", capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "seed" in lines[0] and str(state) in lines[0]
    state.write_text("{not json")
    r = subprocess.run(command(state, out), input="h\n", capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "not a blind-test state file" in r.stderr


ACCEPTED = {"h", "s", "r", "10 7 4 2", "9 6 4 1"}  # the answers of ANSWERS that are saved (others are refused)


def saved_items(state: dict) -> int:
    """Answers plus accepted ratings in a state file."""
    return sum(len(r["answers"]) + (r["ratings"] is not None) for r in state["records"])


@pytest.fixture(scope="module")
def reference_state(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    r = subprocess.run(command(d / "s.json", d / "o.json"), input="\n".join(ANSWERS) + "\n", capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads((d / "s.json").read_text())


@pytest.mark.parametrize("k", [2, 5, 9, 12, 16, len(ANSWERS)])
def test_killed_while_saving_the_state_file_is_whole(tmp_path, reference_state, k):
    """SIGKILL right after the k-th answer is sent (while it is being saved): the state file exists, is
    whole JSON, holds every answer before the k-th and at most the k-th too, each one the reference's."""
    state, out = tmp_path / "s.json", tmp_path / "o.json"
    answer_then_kill(state, out, k)
    saved = json.loads(state.read_text())  # exists (the answers before the k-th were saved) and is whole
    assert saved["study"] == "blind-test" and not out.exists()
    lo = sum(a in ACCEPTED for a in ANSWERS[:k - 1])
    hi = sum(a in ACCEPTED for a in ANSWERS[:k])
    assert lo <= saved_items(saved) <= hi
    for rec, ref in zip(saved["records"], reference_state["records"]):
        assert rec["answers"] == ref["answers"][:len(rec["answers"])]
        assert rec["ratings"] in (None, ref["ratings"])


def test_rehearsal_on_the_simulated_stylus_pokes_through_the_chain(tmp_path):
    from teleop.apps.protocols.blind.human import Coordinator, run_human_study
    from teleop.apps.protocols.blind.participants import ParticipantParams
    from teleop.apps.protocols.blind.rig import RehearsalStation, RigOptions

    answers = iter(["h", "h", "h", "h", "h", "h", "10 7 4 2"])
    out = []
    coordinator = Coordinator(lambda: next(answers, "") + "\n", out.append)
    station = RehearsalStation(RigOptions(), ParticipantParams(speed=0.04))
    station.open()
    try:
        result = run_human_study(tmp_path / "s.json", 5, 1, station.areas, coordinator, station.poke_and_describe)
    finally:
        station.close()
    text = "".join(out)
    felt = [line for line in text.splitlines() if "rehearsal rig: pushed" in line]
    assert len(felt) == 4  # zones 1 and 2, then 3, then 4: each felt once
    forces = [float(line.split("peak force ")[1].split(" N")[0]) for line in felt]
    assert all(0.1 < f <= 0.88 for f in forces)
    assert result is not None and result.records[0].ratings and json.loads((tmp_path / "s.json").read_text())
