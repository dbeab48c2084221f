"""The catalogue's listing, read from the registry: one row per registered effect (what docs/diagnosis.md's
catalogue table shows, and a test keeps it equal to the registry).

`catalogue_rows()` gives the rows as dicts, `catalogue_table()` the markdown table, and
`python -m teleop.core.physics.catalogue FILE` rewrites the table between the markers BEGIN and END in FILE.
"""

from __future__ import annotations

import sys
from pathlib import Path

from teleop.core.physics.base import REGISTRY, Effect, alike

BEGIN = "<!-- catalogue table: generated from the registry by `python -m teleop.core.physics.catalogue` -->"
END = "<!-- end of the catalogue table -->"


def catalogue_row(eff: Effect) -> dict:
    """One effect's row: name, link, channel, inputs -> output, parameters with units, primary parameters,
    what it cannot be told apart from (either way round; and the baseline effects it is no candidate
    beside), whether it is named as a finding, its fit starts, and whether a generator can conceal it."""
    r = eff.rules
    return {"effect": eff.name, "link": eff.link, "channel": r.channel,
            "signals": ", ".join(eff.inputs + tuple(f"[{c}]" for c in eff.optional)) + " -> " + eff.output,
            "params": ", ".join(f"{p.name} [{p.unit}]" for p in eff.params),
            "primary": ", ".join(r.primary),
            "alike": ", ".join([n for n in REGISTRY if n != eff.name and alike(eff.name, n)]
                               + [f"{n} (in the baseline)" for n in r.not_beside]),
            "finding": r.finding, "starts": r.starts, "generated": r.draw is not None}


def catalogue_rows() -> list[dict]:
    """Every registered effect's row, in registry order."""
    return [catalogue_row(e) for e in REGISTRY.values()]


def catalogue_table() -> str:
    """The rows as a markdown table (no trailing newline)."""
    head = ("| effect | link | channel | inputs -> output | parameters | primary | cannot be told apart from "
            "| named | fit starts | generated |")
    lines = [head, "|" + "---|" * 10]
    for r in catalogue_rows():
        lines.append(f"| {r['effect']} | {r['link']} | {r['channel'] or '-'} | {r['signals']} | {r['params']} | "
                     f"{r['primary'] or '-'} | {r['alike'] or '-'} | {'yes' if r['finding'] else 'no'} | "
                     f"{r['starts']} | {'yes' if r['generated'] else '-'} |")
    return "\n".join(lines)


def with_table(text: str) -> str:
    """`text` with the table between BEGIN and END replaced by `catalogue_table()`."""
    if BEGIN not in text or END not in text:
        raise ValueError("the catalogue table's markers are missing")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{BEGIN}\n{catalogue_table()}\n{END}{tail}"


def main(argv: list[str]) -> int:
    """Rewrite the catalogue table in each file of argv."""
    for name in argv:
        path = Path(name)
        path.write_text(with_table(path.read_text(encoding="utf-8")), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
