"""The recording's channel of the distal FBG sensors (`sim://robot?sensor=fbg|one`, seed 001): TOPIC_FBG.

One message per robot reading (gated on `fbg_new`), its JSON schema made from these signals like every row
topic's (teleop.io.recording.layout.json_schema). k is the number of cables that carry an FBG (fbg: 6, one: 1;
a field of width 1 is a number, not a list, as on every row topic):

    fbg_new            1 on a tick with a new robot reading that carries FBG shifts (the gate)
    fbg_cable (k)      the instrumented cables' indices (0-based)
    fbg_dl1_pm (k)     FBG1's Bragg shift [pm] (strain-free: temperature)
    fbg_dl2_pm (k)     FBG2's Bragg shift [pm] (force and temperature)
    fbg_force (k)      the distal tension seed 001 eq 3 gives, (dl2 - r dl1) / S [N]
and for sensor kind one (the sensor-model approach):
    proximal (6)       every cable's proximal (FSR) tension [N]; the distal ones are /estimation tensions
    rest               1 while the rest identification runs (teleop.core.estimation.sensor_reading)
    rest_ratio         its distal/proximal ratio rho (kept once the robot moves)
"""

from __future__ import annotations

from teleop.io.recording.layout import INT, Signal

TOPIC_FBG = "/sensors/fbg"
GATE = "fbg_new"


def fbg_signals(n_fbg: int, one: bool) -> list:
    """The TOPIC_FBG signals (module docstring) for `n_fbg` instrumented cables; `one`: the one-sensor fields."""
    sig = [Signal(TOPIC_FBG, GATE, 1, INT), Signal(TOPIC_FBG, "fbg_cable", n_fbg, INT),
           Signal(TOPIC_FBG, "fbg_dl1_pm", n_fbg), Signal(TOPIC_FBG, "fbg_dl2_pm", n_fbg),
           Signal(TOPIC_FBG, "fbg_force", n_fbg)]
    if one:
        sig += [Signal(TOPIC_FBG, "proximal", 6), Signal(TOPIC_FBG, "rest", 1, INT), Signal(TOPIC_FBG, "rest_ratio")]
    return sig
