"""A recording's links: which links it holds, their data (smoothed inputs, known parameters) and their baseline fit.

The link model itself (Link, LinkData, LinkModel, the effect chain and its prediction) is
teleop.core.physics.links, shared with the simulation and the estimator.
"""

from __future__ import annotations

import numpy as np

from teleop.core.errors import InputError
from teleop.core.physics.base import REGISTRY, get_effect
from teleop.core.physics.links import Link, LinkData, LinkModel, is_exact, noise_sigma
from teleop.io.recording_io import Recording

# width [s] of the zero-phase moving average on the recorded inputs (drive position, load, indentation):
# encoder quantisation and sensor noise on an input would otherwise reach the rate estimates (sign(v)
# flicker at reversals) and let hysteretic models win by filtering the noise instead of by physics
SMOOTH_S = 0.02
SMOOTH_MAX_S = 0.06   # noisier inputs are smoothed more, up to this width, so that the noise left on
RATE_NOISE = 0.02     # their rate is at most this fraction of the rate's 99th percentile


def smooth_width(x: np.ndarray, dt: float) -> int:
    """Odd moving-average width [samples] for input x sampled every dt: enough that the rate noise (sigma /
    (w dt) after a w-sample average and a central difference, sigma from `noise_sigma`) stays below
    RATE_NOISE of the rate's 99th percentile, at least SMOOTH_S and at most SMOOTH_MAX_S; an exact signal
    (no noise, no quantisation: a commanded position) is not smoothed."""
    if is_exact(x):
        return 1
    hi = max(1, int(round(SMOOTH_MAX_S / dt)))
    sigma = noise_sigma(x)
    lo = max(1, int(round(SMOOTH_S / dt))) if sigma > 0 else 1
    v99 = float(np.percentile(np.abs(np.gradient(smooth(x, lo | 1), dt)), 99))
    need = sigma / (RATE_NOISE * v99 * dt) if v99 > 0 else 0.0
    return int(min(max(lo, need), hi)) | 1


def find_links(rec: Recording) -> list[Link]:
    """The links `rec` holds, position first; InputError when it holds none.

    With `load = spring`, no tip position and a tip force, the tip force against the motor position is a
    position link (tip_force = spring gain * tip travel + preload): play and the tip force sensor's own
    effects show there and nowhere else.
    """
    links = []
    ch = rec.channels
    if "motor_pos" in ch and "tip_pos" in ch:
        load = "tip_force" if "tip_force" in ch else ("motor_force" if "motor_force" in ch else None)
        if rec.metadata.get("load") == "spring":
            load = None   # a spring's force is its travel: a stretch by it is a gain, not a finding
        links.append(Link("position", "tip_pos", "motor_pos", "motor_pos", load))
    if "tip_force" in ch and rec.metadata.get("load") == "spring" and ("tip_pos" in ch or "motor_pos" in ch):
        # the spring law: tip force against the tip's travel (the motor's, where the tip is not recorded)
        travel = "tip_pos" if "tip_pos" in ch else "motor_pos"
        links.append(Link("position", "tip_force", travel, "motor_pos" if "motor_pos" in ch else travel))
    if "motor_force" in ch:
        drive = next((c for c in ("actuator_pos", "motor_pos", "tip_pos") if c in ch), None)
        if "tip_force" in ch:
            links.append(Link("force", "motor_force", "tip_force", drive))
        elif rec.metadata.get("load") == "spring" and drive is not None:
            spring = "tip_pos" if "tip_pos" in ch else "motor_pos"
            links.append(Link("force", "motor_force", spring, drive))
    if "indentation" in ch and "force" in ch:
        links.append(Link("contact", "force", "indentation"))
    if not links:
        raise InputError(f"{rec.path}: no link to simulate: channels {', '.join(ch)} (expected motor_pos + "
                         "tip_pos, motor_force + tip_force (or load = spring), or indentation + force)")
    return links


def smooth(x: np.ndarray, width: int) -> np.ndarray:
    """Zero-phase local-line smoothing over odd `width` samples: each sample's value on the least-squares
    line through the samples within half a width of it. Inside the record that is the centred moving
    average; within half a width of either end the window is the one-sided part the record holds, whose
    line neither lags a sloping signal (a one-sided mean lags it by a quarter of the width) nor keeps the
    end sample's own noise (a window shrunk to the end sample does: a stateful effect starts from it)."""
    if width <= 1:
        return x
    n = x.shape[0]
    half = width // 2
    cs = np.concatenate(([0.0], np.cumsum(x)))
    j = np.arange(n)
    a, b = np.maximum(j - half, 0), np.minimum(j + half, n - 1)
    out = (cs[b + 1] - cs[a]) / (b - a + 1)
    for i in np.r_[np.arange(min(half, n)), np.arange(max(n - half, half), n)]:
        k = np.arange(a[i], b[i] + 1, dtype=float)
        if k.size > 1:
            kc = k - k.mean()
            out[i] = out[i] + float(np.dot(kc, x[a[i]:b[i] + 1]) / np.dot(kc, kc)) * (i - k.mean())
    return out


def link_data(rec: Recording, link: Link, corrections: dict | None = None, raw_input: bool = False) -> LinkData:
    """The arrays of `link` from `rec`; inputs (not the output) are smoothed (see smooth_width), except
    the link's input itself with raw_input (a play operator's dead band filters the input's noise on its
    own, and smoothing rounds the reversals it switches at). corrections: {channel: (n,) array}
    subtracted from a recorded channel before use (a sensor effect identified on another link, taken out
    of this link's input)."""
    ch = dict(rec.channels)
    for name, c in (corrections or {}).items():
        if name in ch:
            ch[name] = ch[name] - c
    dt = rec.dt

    widths = []

    def sm(name):
        w = smooth_width(ch[name], dt)
        widths.append(w)
        return smooth(ch[name], w)

    x = sm(link.drive) if link.drive and link.kind != "contact" else None
    u = ch[link.input] if raw_input else sm(link.input)
    load = sm(link.load) if link.load else None
    temp = sm("temperature") if "temperature" in ch else None
    return LinkData(link, rec.t, u, ch[link.output], x, load, temp, ch.get("bend_angle"), max(widths) * dt,
                    known_params(rec))


def known_params(rec: Recording) -> dict:
    """{effect: {param: value}} from the recording's metadata keys `EFFECT.PARAM = VALUE` (SI, the
    catalogue's parameter units): parameters the user's simulation already has, held at that value
    wherever the effect is fitted (a simulated robot's sheath friction coefficient, say). Keys whose prefix
    is not a catalogue effect are other metadata; an unknown parameter of a catalogue effect, or a value
    that is not a number, raises InputError naming the key."""
    out = {}
    for key, text in rec.metadata.items():
        name, _, param = str(key).partition(".")
        if not param or name not in REGISTRY:
            continue
        eff = get_effect(name)
        if param not in {s.name for s in eff.params}:
            raise InputError(f"{rec.path}: metadata '{key}': effect '{name}' has no parameter '{param}' "
                             f"(expected one of {', '.join(s.name for s in eff.params)})")
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"{rec.path}: metadata '{key}' = '{text}': expected a number") from None
        if not np.isfinite(value):
            raise InputError(f"{rec.path}: metadata '{key}' = '{text}': expected a finite number")
        out.setdefault(name, {})[param] = value
    return out


def fit_baseline(d: LinkData, index) -> LinkModel:
    """Least-squares gain and offset of the ideal link on samples `index`; direction and load sign from
    the residual's correlation with the motion direction and the load."""
    u = np.maximum(d.u, 0.0) if d.link.kind == "contact" else d.u
    A = np.column_stack([u[index], np.ones(u[index].shape)])
    (g, c), *_ = np.linalg.lstsq(A, d.y[index], rcond=None)
    r = d.y - (g * u + c)
    direction, load_sign = 1.0, 1.0
    if d.x is not None:
        s = np.sign(np.gradient(d.x))[index]
        if d.link.kind == "force":
            direction = 1.0 if float(np.dot(s, r[index])) >= 0 else -1.0
    if d.link.kind == "position" and d.load is not None:
        # stretch: the tip falls short of the motor by load / k; choose the load sign that makes it so
        ld = d.load[index] - np.mean(d.load[index])
        load_sign = -1.0 if float(np.dot(ld, r[index])) >= 0 else 1.0
    return LinkModel(d.link, float(g), float(c), direction, load_sign)
