"""The house in layers (docs/architecture.md): the import-linter contracts hold, and no function-local import of
the project's own modules hides an import that runs the wrong way."""

from __future__ import annotations

import ast
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OWN = ("teleop", "devices", "scenes")


def local_imports_of_own_modules(root: Path = ROOT) -> list[str]:
    """`file:line module` for every import of teleop/devices/scenes that is not at a module's top level
    (inside a function, method or class body)."""
    found = []
    for package in OWN:
        for path in sorted((root / package).rglob("*.py")):
            tree = ast.parse(path.read_text(), filename=str(path))
            top = set()
            stack = list(tree.body)
            while stack:   # module level, including under if / try (TYPE_CHECKING, optional dependencies)
                node = stack.pop()
                top.add(id(node))
                for field in ("body", "orelse", "finalbody", "handlers"):
                    stack.extend(n for n in getattr(node, field, []) if isinstance(node, (ast.If, ast.Try))
                                 or isinstance(n, ast.ExceptHandler))
            for node in ast.walk(tree):
                if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in top:
                    names = [node.module or ""] if isinstance(node, ast.ImportFrom) else [a.name for a in node.names]
                    if isinstance(node, ast.ImportFrom) and node.level:
                        names = ["." * node.level + (node.module or "")]
                    for name in names:
                        if name.split(".")[0] in OWN or name.startswith("."):
                            found.append(f"{path.relative_to(root)}:{node.lineno} {name}")
    return found


def test_no_function_local_import_of_own_modules():
    assert local_imports_of_own_modules() == []


def test_the_finder_sees_a_local_import(tmp_path):
    pkg = tmp_path / "teleop"
    pkg.mkdir()
    (pkg / "m.py").write_text("import os\n\ndef f():\n    from teleop.core import errors\n    return errors\n")
    for other in ("devices", "scenes"):
        (tmp_path / other).mkdir()
    assert local_imports_of_own_modules(tmp_path) == ["teleop/m.py:4 teleop.core"]


def test_import_contracts_are_kept():
    exe = shutil.which("lint-imports")
    assert exe, "lint-imports not found: install the test extra (pip install -e '.[test]')"
    run = subprocess.run([exe, "--no-cache"], cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
