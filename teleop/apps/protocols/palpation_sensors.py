"""The palpation tests with the FBG sensor kinds (`teleop palpate --sensor fbg|one`) and the seed figures
they are read against.

- fbg: the estimate from every cable's distal FBG (teleop.core.estimation.sensor_reading).
- one: the FSR array plus cable `cable`'s distal FBG; Kp and Kr of seed 001 eq 7 are identified on that cable
  over the test's no-load runs (the same back-and-forth runs the FSR estimators' turn and friction fits use:
  the cable is hauled in and paid out at its pretension, so its proximal tension swings between Fd / Kp
  and Fd / Kr), then applied to the other five.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from teleop.apps.protocols.palpation_estimators import ESTIMATORS, fsr_tensions, slice_trace
from teleop.core.errors import InputError
from teleop.core.estimation.sensor_reading import estimate_trace, identify_one_sensor
from teleop.core.sensors import FbgParams
from teleop.io.calfile import load_calibration

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


def sensor_calibration(path: str | None, kind: str) -> dict:
    """The estimator's settings from a `teleop calibrate` file for sensor `kind` ({} without a file):
    {"fbg": FbgParams} from a kind "fbg" file (sensor fbg or one), {"model": ProximalDistalModel} from a
    kind "one-sensor" file (sensor one: used instead of identifying it). Any other pairing is an
    InputError naming the file."""
    if path is None:
        return {}

    file_kind, value = load_calibration(path)
    if file_kind == "fbg" and kind in ("fbg", "one"):
        return {"fbg": value}
    if file_kind == "one-sensor" and kind == "one":
        return {"model": value}
    if kind == "fsr":
        raise InputError(f"{path}: --sensor fsr takes no --calibration here (the FSR array's estimators read the "
                         f"simulated robot's own FSR calibration); --calibration is for --sensor fbg or one")
    wants = {"fbg": 'kind = "fbg"', "one": 'kind = "fbg" or "one-sensor"'}[kind]
    raise InputError(f"{path}: kind = \"{file_kind}\" does not calibrate --sensor {kind} (expected {wants})")


def sensor_estimates(kind: str, fit_trace, spans: dict, poke_trace, geom, dt: float, cable: int = 0,
                     progress=None, calibration: str | None = None) -> tuple[dict, dict]:
    """({estimator: (m, 6) wrench} over `poke_trace`, calibration record) for sensor kind fbg or one.

    spans: {axis: (a, b)} sample ranges of `fit_trace` holding the no-load runs; calibration: a `teleop
    calibrate` file (`sensor_calibration`). The record holds `tension_rmse_N`: per cable, the RMSE of the
    tip tensions read against the simulation's over the poke runs."""
    cal = sensor_calibration(calibration, kind)
    fbg, model, calib = cal.get("fbg", FbgParams()), cal.get("model"), {"sensor": kind}
    if calibration is not None:
        calib["calibration_file"] = str(calibration)
        calib["fbg"] = asdict(fbg)
    if kind == "one" and model is not None:
        calib["one_sensor"] = {"cable": cable, **asdict(model)}
    elif kind == "one":
        a, b = min(v[0] for v in spans.values()), max(v[1] for v in spans.values())
        sl = slice(a, b)
        Fp = fsr_tensions(slice_trace(fit_trace, a, b))
        model = identify_one_sensor(Fp[:, cable], fit_trace.fbg_pm[sl], fit_trace.lengths[sl, cable], cable, fbg)
        # what the sheath's capstan law gives the instrumented cable over the run (exp(-+mu Theta))
        mt = geom.mu * fit_trace.theta[sl, cable]
        calib["one_sensor"] = {"cable": cable, "Kp": round(model.Kp, 6), "Kr": round(model.Kr, 6),
                               "capstan_Kp_range": [round(float(np.exp(-mt.max())), 6), round(float(np.exp(-mt.min())), 6)],
                               "capstan_Kr_range": [round(float(np.exp(mt.min())), 6), round(float(np.exp(mt.max())), 6)]}
    t = np.empty(poke_trace.t_tip.shape)
    w = estimate_trace(poke_trace, geom, dt, kind, ESTIMATORS, fbg=fbg, model=model, cable=cable, progress=progress,
                       tensions_out=t)
    # how well each cable's tip tension is read over the poke runs (the simulation's own tip tensions)
    calib["tension_rmse_N"] = [round(float(v), 6) for v in np.sqrt(np.mean((t - poke_trace.t_tip) ** 2, axis=0))]
    return w, calib


def sensor_lines(result) -> list:
    """Plain-text lines for a palpation result of an FBG kind: what the names mean, each session's per-cable
    tension RMSE and the seed figures."""
    kind = result.params["sensor"]
    lines = [f"sensor: {kind} (tip-side tensions: every estimator name runs the same f = -A t and Kalman; "
             f"teleop.core.estimation.sensor_reading)"]
    for name, c in result.extra.get("calibration", {}).items():
        rmse = c.get("sensor", {}).get("tension_rmse_N")
        if rmse:
            lines.append(f"{name}: tip tension RMSE per cable [N]: " + " ".join(f"{v:.3f}" for v in rmse))
    return lines + ["the sources' figures:"] + seed_lines(kind)


def seed_lines(kind: str) -> list:
    """Plain-text lines of the seed figures to read a `kind` result against."""
    keys = [k for k in SEED_FIGURES if k.startswith("seed 000")]
    if kind == "fbg":
        keys += [k for k in SEED_FIGURES if "FBG" in k]
    elif kind == "one":
        keys += [k for k in SEED_FIGURES if "FBG sensor error" in k or "sensor-model" in k]
    return [f"  {k}: {SEED_FIGURES[k]:.3f} N" for k in keys]
