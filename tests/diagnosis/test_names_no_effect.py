"""The diagnosis, the generators and the bench read each effect's rules from the registry: their code (string
literals outside docstrings and comments) names no registered effect."""

import ast
from pathlib import Path

import pytest

from teleop.core.physics import REGISTRY

ROOT = Path(__file__).resolve().parents[2]
FILES = ("teleop/diagnosis/identify.py", "teleop/diagnosis/generator.py", "scenes/cable_rig.py",
         "teleop/apps/bench/diagnose_rig.py", "teleop/diagnosis/diagnose.py")


def _literals(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.FunctionDef, ast.ClassDef)) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    return [n.value for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs]


@pytest.mark.parametrize("name", FILES)
def test_code_names_no_registered_effect(name):
    named = sorted({e for s in _literals(ROOT / name) for e in REGISTRY if e in s})
    assert not named, f"{name} names {named}: put the rule on the effect (teleop.core.physics.base.Rules)"
