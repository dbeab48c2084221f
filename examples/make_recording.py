"""Write the example recordings of this folder (run from the repository root; output is reproducible):

    python examples/make_recording.py

- recording.csv: a 10 s, 200 Hz single-cable rig recording in the interchange format (docs/formats.md),
  simulated by teleop.diagnosis.generator (case 0 of seed 0) with one effect the diagnosis tool is meant to
  find: backlash between motor and tip (play 2.33 mm).
- rig_raw.txt: the same samples as a rig's data logger might write them (semicolons, no header, time in
  ms, encoder counts, force in ADC counts), read through column_map.toml.
"""

from pathlib import Path

import numpy as np

from teleop.diagnosis.generator import GenConfig, case_plan, make_case

HERE = Path(__file__).resolve().parent
COUNTS_PER_MM = 100.0  # encoder counts per mm (rig_raw.txt)
N_PER_COUNT = 0.005    # force sensor [N per ADC count] (rig_raw.txt)


def main() -> None:
    effect, setup = case_plan(1)[0]
    case = make_case(0, effect, setup, seed=0, cfg=GenConfig(fs_hz=200.0, duration_s=10.0))
    (HERE / "recording.csv").write_text(case.csv, encoding="utf-8")
    lines = [ln for ln in case.csv.splitlines() if not ln.startswith("#")]
    header = lines[0].split(",")
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    col = {name: data[:, header.index(name)] for name in header}
    raw = np.column_stack([np.round(col["t_s"] * 1e3), np.round(col["motor_pos_mm"] * COUNTS_PER_MM),
                           np.round(col["tip_pos_mm"] * COUNTS_PER_MM),
                           np.round(col["motor_force_N"] / N_PER_COUNT), np.round(col["tip_force_N"] / N_PER_COUNT)])
    text = "# rig logger export: ms; motor counts; tip counts; motor force counts; tip force counts\n"
    text += "\n".join(";".join(str(int(v)) for v in row) for row in raw) + "\n"
    (HERE / "rig_raw.txt").write_text(text, encoding="utf-8")
    print(f"wrote recording.csv ({effect}, {case.params}) and rig_raw.txt: {len(raw)} samples")


if __name__ == "__main__":
    main()
