"""The palpation tests with the FBG sensor kinds (`teleop palpate --sensor fbg|one`) and the seed figures
they are read against.

- fbg: the estimate from every cable's distal FBG (teleop.estimation.sensor_reading).
- one: the FSR array plus cable `cable`'s distal FBG; Kp and Kr of seed 001 eq 7 are identified on that cable
  over the test's no-load runs (the same back-and-forth runs the FSR estimators' turn and friction fits use:
  the cable is hauled in and paid out at its pretension, so its proximal tension swings between Fd / Kp
  and Fd / Kr), then applied to the other five.
"""

from __future__ import annotations

import numpy as np

#: the sources' figures, for the side-by-side tables (N)
SEED_FIGURES = {
    "seed 000 z palpation MAE (FSR array, double compensation, hardware)": 0.173,
    "seed 000 z palpation RMSE": 0.213,
    "seed 000 x/y palpation MAE": 0.268,
    "seed 001 FBG sensor error (RMSE of the shift / S)": 0.37,
    "seed 001 FBG max error under 24 degC of heating, compensated (unfiltered)": 0.94,
    "seed 001 FBG max error under heating, uncompensated": 18.44,
    "seed 001 sensor-model RMSE, two TSMs": 0.36,
    "seed 001 sensor-model RMSE, endoscopic robot": 0.65,
}


def sensor_estimates(kind: str, fit_trace, spans: dict, poke_trace, geom, dt: float, cable: int = 0,
                     progress=None) -> tuple[dict, dict]:
    """({estimator: (m, 6) wrench} over `poke_trace`, calibration record) for sensor kind fbg or one.

    spans: {axis: (a, b)} sample ranges of `fit_trace` holding the no-load runs."""
    from teleop.estimation.sensor_reading import estimate_trace, identify_one_sensor
    from teleop.protocols.palpation import ESTIMATORS, _slice, fsr_tensions

    model, calib = None, {"sensor": kind}
    if kind == "one":
        a, b = min(v[0] for v in spans.values()), max(v[1] for v in spans.values())
        sl = slice(a, b)
        Fp = fsr_tensions(_slice(fit_trace, a, b))
        model = identify_one_sensor(Fp[:, cable], fit_trace.fbg_pm[sl], fit_trace.lengths[sl, cable], cable)
        # what the sheath's capstan law gives the instrumented cable over the run (exp(-+mu Theta))
        mt = geom.mu * fit_trace.theta[sl, cable]
        calib["one_sensor"] = {"cable": cable, "Kp": round(model.Kp, 6), "Kr": round(model.Kr, 6),
                               "capstan_Kp_range": [round(float(np.exp(-mt.max())), 6), round(float(np.exp(-mt.min())), 6)],
                               "capstan_Kr_range": [round(float(np.exp(mt.min())), 6), round(float(np.exp(mt.max())), 6)]}
    w = estimate_trace(poke_trace, geom, dt, kind, ESTIMATORS, model=model, cable=cable, progress=progress)
    return w, calib


def seed_lines(kind: str) -> list:
    """Plain-text lines of the seed figures to read a `kind` result against."""
    keys = [k for k in SEED_FIGURES if k.startswith("seed 000")]
    if kind == "fbg":
        keys += [k for k in SEED_FIGURES if "FBG" in k]
    elif kind == "one":
        keys += [k for k in SEED_FIGURES if "FBG sensor error" in k or "sensor-model" in k]
    return [f"  {k}: {SEED_FIGURES[k]:.3f} N" for k in keys]
