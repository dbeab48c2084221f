"""The blind study with real participants: prompts for the coordinator, answers saved after every step.

The state file (JSON, written atomically and fsynced after every answer) holds the seed, the areas and,
per participant, the pad layout, the presentation order, every answer and the ratings. The protocol's next
question is a pure function of the answers (`protocol.next_step`), so running the same command again
resumes exactly where an interrupted study stopped.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from teleop.apps.protocols.blind.protocol import (ANSWERS, HARDER, SOFTER, UNSURE, Compare, Rate, check_ratings,
                                                  next_step)
from teleop.apps.protocols.blind.study import ParticipantRecord, StudyResult, coordinator_draws
from teleop.core.errors import InputError
from teleop.io.outputs import dumps_json, write_text_synced

STATE_FORMAT = 1
SLOT_NAMES = "ABCDEFGH"
_ALIASES = {"h": HARDER, "harder": HARDER, "s": SOFTER, "softer": SOFTER,
            "r": UNSURE, "u": UNSURE, "unsure": UNSURE, "repeat": UNSURE}


def save_state(path: Path, state: dict) -> None:
    """Write the state atomically (temp file, fsync, rename): the file is always a whole answer set."""
    write_text_synced(path, dumps_json(state))


def new_state(seed: int, participants: int, areas) -> dict:
    return {"study": "blind-test", "format": STATE_FORMAT, "seed": int(seed), "participants": int(participants),
            "areas": [a.name for a in areas], "records": []}


def load_state(path: Path, seed: int, participants: int, areas) -> dict:
    """Read a state file and check it belongs to this study (same seed, participants and areas)."""
    try:
        state = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not a blind-test state file (invalid JSON at line {exc.lineno})") from None
    if not isinstance(state, dict) or state.get("study") != "blind-test" or state.get("format") != STATE_FORMAT:
        raise InputError(f"{path}: not a blind-test state file (expected study = blind-test, format = 1)")
    expected = {"seed": int(seed), "participants": int(participants), "areas": [a.name for a in areas]}
    for key, value in expected.items():
        if state.get(key) != value:
            raise InputError(f"{path}: key '{key}' is {state.get(key)!r} but this run asks for {value!r} "
                             f"(use the same options to resume, or a new --state file)")
    records = state.get("records")
    if not isinstance(records, list):
        raise InputError(f"{path}: key 'records' must be a list")
    for i, rec in enumerate(records):
        ok = (isinstance(rec, dict) and rec.get("participant") == i + 1 and isinstance(rec.get("answers"), list)
              and all(isinstance(a, list) and len(a) == 3 and a[2] in ANSWERS for a in rec["answers"]))
        if not ok:
            raise InputError(f"{path}: records[{i}] is malformed (expected participant {i + 1} with answers "
                             f"[new zone, reference zone, harder|softer|unsure])")
    return state


def replay(rec: dict, n_zones: int, where: str) -> list:
    """[(Compare, answer)] rebuilt from a record's saved answers, checked against the protocol."""
    answers = []
    for k, (new, ref, answer) in enumerate(rec["answers"]):
        step = next_step(n_zones, answers)
        if not isinstance(step, Compare) or (step.new + 1, step.ref + 1) != (new, ref):
            raise InputError(f"{where}: answers[{k}] = {[new, ref, answer]} does not follow the protocol")
        answers.append((step, answer))
    return answers


class Coordinator:
    """Prompts on `write`, answers from `read` (returns one line, '' at end of input)."""

    def __init__(self, read: Callable[[], str], write: Callable[[str], None]):
        self.read = read
        self.write = write

    def ask(self, prompt: str) -> str:
        self.write(prompt)
        line = self.read()
        if line == "":
            raise EOFError
        return line.strip().lower()

    def comparison(self, step: Compare) -> str:
        z_new, z_ref = step.new + 1, step.ref + 1
        while True:
            text = self.ask(f"Is zone {z_new} harder or softer than zone {z_ref}? "
                            f"[h = harder, s = softer, r = unsure: poke both again] ")
            if text in _ALIASES:
                return _ALIASES[text]
            self.write(f"  '{text}' is not an answer: type h (zone {z_new} is harder), s (zone {z_new} is "
                       f"softer) or r (unsure: poke zones {z_ref} and {z_new} again)\n")

    def ratings(self, ranking) -> list:
        zones = ", ".join(f"zone {z + 1}" for z in ranking)
        while True:
            text = self.ask(f"Ratings from hardest to softest ({zones}): {len(ranking)} whole numbers, "
                            f"hardest 8-10, softest 1-3, decreasing: ")
            try:
                values = [int(v) for v in text.replace(",", " ").split()]
                check_ratings(ranking, values)
                return values
            except ValueError as exc:
                msg = str(exc) if isinstance(exc, InputError) else f"'{text}' is not {len(ranking)} whole numbers"
                self.write(f"  refused: {msg}; please enter them again\n")


def run_human_study(state_path, seed: int, participants: int, areas, coordinator: Coordinator,
                    station: Callable[[tuple, int], str] | None = None,
                    on_step: Callable[[dict], None] | None = None) -> StudyResult | None:
    """Guide the coordinator through the study; returns the result when every participant is done.

    station(layout, slot) -> str, optional: pokes a slot on a rehearsal rig and says what the stylus felt.
    on_step(event), optional: told each step (the experimenter's live view, teleop.loop.live.study): kind
    "participant" (layout, order_slots), "compare" (zones and slots), "answer", "ratings".
    Returns None when input ends early (everything answered so far is saved in `state_path`).
    """
    tell = on_step or (lambda event: None)
    path = Path(state_path)
    areas = tuple(areas)
    n = len(areas)
    state = load_state(path, seed, participants, areas) if path.exists() else new_state(seed, participants, areas)
    labels = {a.name: a.label for a in areas}
    say = coordinator.write
    if not path.exists():
        save_state(path, state)
    else:
        done = sum(1 for r in state["records"] if r.get("ratings") is not None)
        say(f"Resuming {path}: {done} of {participants} participants done.\n")
    try:
        for p in range(1, participants + 1):
            if len(state["records"]) < p:
                layout, order = coordinator_draws(seed, p, areas)
                state["records"].append({"participant": p, "layout": list(layout), "order_slots": list(order),
                                         "answers": [], "ratings": None})
                save_state(path, state)
            rec = state["records"][p - 1]
            if rec.get("ratings") is not None:
                continue
            layout, order = rec["layout"], rec["order_slots"]
            where = f"{path}: records[{p - 1}]"
            answers = replay(rec, n, where)
            say(f"\n== Participant {p} of {participants} ==\n")
            tell({"kind": "participant", "participant": p, "of": participants, "layout": list(layout),
                  "order_slots": list(order), "answers": [list(a) for a in rec["answers"]]})
            say("Coordinator: lay out the pad as " + ", ".join(
                f"slot {SLOT_NAMES[i]} = {labels[name]}" for i, name in enumerate(layout)) + ".\n")
            say("Zones (coordinator only): " + ", ".join(
                f"zone {z + 1} = slot {SLOT_NAMES[s]}" for z, s in enumerate(order)) + ".\n")
            step = next_step(n, answers)
            while isinstance(step, Compare):
                tell({"kind": "compare", "participant": p, "question": len(answers) + 1, "new_zone": step.new + 1,
                      "ref_zone": step.ref + 1, "new_slot": order[step.new], "ref_slot": order[step.ref],
                      "repeat": step.repeat})
                _announce(step, answers, layout, order, say, station)
                answer = coordinator.comparison(step)
                rec["answers"].append([step.new + 1, step.ref + 1, answer])
                save_state(path, state)
                tell({"kind": "answer", "participant": p, "new_zone": step.new + 1, "ref_zone": step.ref + 1,
                      "answer": answer, "answers": [list(a) for a in rec["answers"]]})
                answers.append((step, answer))
                step = next_step(n, answers)
            assert isinstance(step, Rate)
            rec["ratings"] = coordinator.ratings(step.ranking)
            rec["ranking_zones"] = [z + 1 for z in step.ranking]
            save_state(path, state)
            tell({"kind": "ratings", "participant": p, "ratings": rec["ratings"],
                  "ranking_zones": rec["ranking_zones"]})
            say(f"Participant {p} saved.\n")
    except EOFError:
        say(f"\nInput ended: every answer so far is saved in {path}; run the same command again to resume.\n")
        return None
    return result_from_state(state, areas)


def _announce(step: Compare, answers, layout, order, say, station) -> None:
    """Tell the coordinator which zones to poke: on a new question the ones not felt yet (the others are
    compared from memory, as in the seed), on an unsure answer both again."""
    felt = {z for s, _ in answers for z in (s.new, s.ref)}
    if step.repeat == 0:
        say(f"\nCompare zone {step.new + 1} with zone {step.ref + 1}.\n")
        zones = [z for z in (step.ref, step.new) if z not in felt]
        if not zones:
            say("  (both already felt: the participant compares from memory; r asks to poke both again)\n")
    else:
        say(f"\nUnsure ({step.repeat}): poke zone {step.ref + 1} and zone {step.new + 1} again.\n")
        zones = [step.ref, step.new]
    for z in zones:
        slot = order[z]
        say(f"  move the effector over zone {z + 1} (slot {SLOT_NAMES[slot]}); the participant pushes.\n")
        if station is not None:
            say(f"    rehearsal rig: {station(tuple(layout), slot)}\n")


def result_from_state(state: dict, areas) -> StudyResult:
    """The StudyResult of a finished state file (no rendered stiffness: real pokes are not traced)."""
    records = []
    for rec in state["records"]:
        layout, order = rec["layout"], rec["order_slots"]
        zone_area = [layout[s] for s in order]
        ranking = [zone_area[z - 1] for z in rec["ranking_zones"]]
        records.append(ParticipantRecord(
            participant=rec["participant"], layout=tuple(layout), order=tuple(zone_area),
            answers=tuple(tuple(a) for a in rec["answers"]), ranking=tuple(ranking),
            ratings={a: int(r) for a, r in zip(ranking, rec["ratings"])}))
    return StudyResult(areas=tuple(areas), records=tuple(records), config={"operator": "human",
                                                                          "seed": state["seed"]})
