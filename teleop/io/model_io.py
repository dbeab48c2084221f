"""Save an identified model and load it back into the simulated robot and the estimator.

File (JSON): {"format": "teleop-link-model/1", "source": recording, "links": [{"kind", "input", "output",
"drive", "load", "gain", "offset", "direction", "load_sign", "baseline_effects", "effects": [{"effect",
"params"}]}]}; the first `baseline_effects` effects are the baseline's (the simulation the recording was
compared with), the rest the findings (`scenes.sim_robot` switches those on: `sim://robot?model=FILE`).
Effect names and parameters are those of the physics registry, so `IdentifiedModel.effects(kind)` can be
handed to any user of teleop.core.physics: `chain_effect(kind)` gives one physics Effect (namespaced params)
and `steps(kind)` per-sample Step objects for a real-time estimator.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from teleop.core.errors import InputError
from teleop.core.physics import get_effect
from teleop.core.physics.base import chain
from teleop.core.physics.links import Link, LinkModel
from teleop.io.outputs import atomic_write, dumps_json

FORMAT = "teleop-link-model/1"


def model2dict(m: LinkModel) -> dict:
    L = m.link
    return {"kind": L.kind, "input": L.input, "output": L.output, "drive": L.drive, "load": L.load,
            "gain": m.gain, "offset": m.offset, "direction": m.direction, "load_sign": m.load_sign,
            "baseline_effects": m.base,
            "effects": [{"effect": n, "params": dict(p)} for n, p in m.effects]}


def dict2model(doc: dict, where: str) -> LinkModel:
    try:
        L = Link(doc["kind"], doc["output"], doc["input"], doc.get("drive"), doc.get("load"))
        effects = []
        for e in doc.get("effects", []):
            eff = get_effect(e["effect"])
            effects.append((eff.name, eff.check(e["params"])))
        base = int(doc.get("baseline_effects", 0))
        if not 0 <= base <= len(effects):
            raise ValueError(f"baseline_effects {base} outside 0..{len(effects)}")
        return LinkModel(L, float(doc["gain"]), float(doc["offset"]), float(doc.get("direction", 1.0)),
                         float(doc.get("load_sign", 1.0)), tuple(effects), base)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{where}: malformed link model ({exc!r})") from None


@dataclass(frozen=True)
class IdentifiedModel:
    """Link models by kind ('position', 'force', 'contact') and the recording they came from."""

    source: str
    links: dict

    def model(self, kind: str) -> LinkModel:
        if kind not in self.links:
            raise InputError(f"identified model has no {kind} link (has: {', '.join(self.links) or 'none'})")
        return self.links[kind]

    def effects(self, kind: str) -> list:
        """[(effect name, params), ...] identified on link `kind`, in chain order."""
        return list(self.model(kind).effects)

    def chain_effect(self, kind: str):
        """One physics Effect chaining the link's identified effects; params as `chain_params(kind)`."""
        names = [n for n, _ in self.effects(kind)]
        if not names:
            raise InputError(f"no effect was identified on the {kind} link")
        return chain(*names)

    def chain_params(self, kind: str) -> dict:
        """Namespaced {"effect.param": value} for `chain_effect(kind)`."""
        return {f"{n}.{k}": v for n, p in self.effects(kind) for k, v in p.items()}

    def steps(self, kind: str) -> list:
        """Fresh per-sample physics Steps of the link's effects (for a real-time simulator or estimator)."""
        return [get_effect(n).make_step(p) for n, p in self.effects(kind)]


def save_model(path: str | Path, models: list, source: str) -> Path:
    """Write link models (list of LinkModel) identified on `source` as JSON, atomically."""
    doc = {"format": FORMAT, "source": source, "links": [model2dict(m) for m in models]}
    text = dumps_json(doc)
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def load_model(path: str | Path) -> IdentifiedModel:
    """Read a model written by `save_model` (or `teleop diagnose --save-model`)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}), expected a link model "
                         f"(JSON)") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: invalid JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise InputError(f"{path}: not a link model (expected \"format\": \"{FORMAT}\")")
    links = {}
    for k, item in enumerate(doc.get("links", [])):
        m = dict2model(item, f"{path}: links[{k}]")
        links[m.link.kind] = m
    return IdentifiedModel(str(doc.get("source", "")), links)
