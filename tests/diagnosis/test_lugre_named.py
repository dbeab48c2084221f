"""The LuGre friction's test scenario: a recording the diagnosis did not make (the test-side generator of
tests.diagnosis._independent: a sheath's capstan pulling a spring, plus a LuGre friction integrated here on
its own, Euler steps of the bristle law in time on a grid SUB times finer than the recording) names
`lugre_friction` first on the motor force with a held-out improvement of at least 2x; the same recording
without it names nothing."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from teleop.core.physics import Signals, get_effect
from teleop.diagnosis.diagnose import diagnose
from teleop.io.recording_io import read_interchange

from tests.diagnosis._independent import SUB, Case, Made, drive, make, motor_tension, write_csv

CASE = Case(ratio=2.0, drive="sine", freq=0.5, amplitude=5e-3, noise_frac=0.004, seconds=20.0, seed=3)
#: the friction's levels [N], Stribeck velocity [m/s] (40 % of the sine's peak speed) and rest stiffness [N/m]
#: (a transition Fs / sigma over 1 % of the amplitude)
FC, FS = 0.4, 1.0
VS = 0.4 * CASE.amplitude * 2 * math.pi * CASE.freq
SIGMA = FS / (0.01 * CASE.amplitude)


def lugre_force(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """LuGre friction [N] without damping along a fine time grid t [s] of the drive's true rate v [m/s]:
    dz/dt = v - sigma |v| z / g(v), F = sigma z, explicit Euler from z = 0."""
    g = FC + (FS - FC) * np.exp(-(v / VS) ** 2)
    z, out = 0.0, np.empty_like(t)
    h = float(t[1] - t[0])
    for i in range(t.size):
        out[i] = SIGMA * z
        z += h * (v[i] - SIGMA * abs(v[i]) * z / g[i])
    return out


def with_lugre(case: Case) -> Made:
    """`make(case)` with the LuGre friction added to the motor tension (the same noise draws)."""
    made = make(case)
    n = made.t.size
    tf = np.arange(n * SUB) / (case.rate * SUB)
    _, vf = drive(case, tf)
    F = lugre_force(tf, vf)[::SUB]
    ch = dict(made.channels, motor_force=made.channels["motor_force"] + F)
    return dataclasses.replace(made, channels=ch, truth={**made.truth, "lugre": F})


def _first(doc: dict, channel: str):
    return next((f for f in doc["findings"] if f["channel"] == channel), None)


@pytest.fixture(scope="module")
def named(tmp_path_factory):
    path = write_csv(with_lugre(CASE), tmp_path_factory.mktemp("lugre") / "lugre.csv")
    return diagnose(read_interchange(path)).as_dict()


def test_lugre_named_first_with_2x(named):
    f = _first(named, "motor_force")
    assert f is not None and f["effect"] == "lugre_friction", named["findings"]
    assert f["improvement"] >= 2.0
    p = f["params"]
    assert abs(p["Fs"]["value"] / FS - 1.0) < 0.3 and abs(p["Fc"]["value"] / FC - 1.0) < 0.3


def test_effect_free_names_nothing(tmp_path):
    path = write_csv(make(CASE), tmp_path / "clean.csv")
    assert diagnose(read_interchange(path)).as_dict()["findings"] == []


def test_kernel_limits_are_dahl_and_stribeck():
    """Fs = Fc is the Dahl law; a very stiff rest is the Stribeck law after the first samples."""
    t = np.arange(4000) / 1000.0
    x = 5e-3 * np.sin(2 * math.pi * 0.5 * t)
    s = Signals(t=t, x=x, load=np.full(t.size, 5.0))
    lugre = get_effect("lugre_friction")
    dahl = lugre.apply(s, {"sigma": 800.0, "Fc": 0.4, "Fs": 0.4, "vs": 1e-3})
    assert np.allclose(dahl, get_effect("dahl_hysteresis").apply(s, {"sigma": 800.0, "Fc": 0.4}))
    stiff = lugre.apply(s, {"sigma": 1e9, "Fc": 0.4, "Fs": 1.0, "vs": 0.005})
    strib = get_effect("stribeck_friction").apply(s, {"Fc": 0.4, "Fs": 1.0, "vs": 0.005})
    moving = np.abs(s.v) > 1e-4
    assert np.allclose(stiff[moving][5:], strib[moving][5:], atol=1e-6)
