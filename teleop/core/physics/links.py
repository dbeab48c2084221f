"""The link model the simulation, the estimator and the diagnosis share: a link, its baseline and its effect chain.

A link maps input channels to one output channel (names as in the interchange recording):

- position link: motor_pos -> tip_pos (load for cable stretch: tip_force, else motor_force; none with
  `load = spring`, where the load is the tip's own travel);
- spring law (`load = spring`, a position link through a spring): tip_pos (else motor_pos) -> tip_force;
  position effects act on the travel in the input's units, the gain is the spring's, and the tip force
  sensor's effects apply to the output;
- force link: tip load -> motor_force, the motor motion (actuator_pos, else motor_pos, else tip_pos) giving
  the direction; with `load = spring` and no tip_force the spring's deflection (tip_pos, else motor_pos) is
  the load. actuator_pos is the actuator's own position where motor_pos is measured past a gearbox or
  coupling: the proximal force sensor sits between the two, so its friction and pre-sliding states follow
  the actuator (a spindle held by static friction while its motor winds the coupling: the torque reverses
  before the spindle moves), while the position link stays motor_pos -> tip_pos;
- contact link: indentation -> force (a pad poke).

Baseline (what every finding is an addition to): an affine map y = g u + c (gain g: transmission ratio
and units; offset c: sensor and encoder zeros) and the first `LinkModel.base` effects of the chain (the
simulation the user already has: by default the sheath's capstan friction on force links). For the contact
link the affine part is the linear contact law, F = g max(d, 0) + c.

With effects, the link's model is a chain of registered physics effects (teleop.core.physics), run on the
referred signals: position: z = g u + c -> E_1 -> E_2 ... = tip; force: L = g u -> E_1 ... + c -> sensor
effects = motor force; contact: contact law (baseline or a catalogue contact effect) + c -> sensor effects.
`direction` (+1/-1) orients the motor motion so that positive motion raises the output's friction side
(sensor sign conventions differ between rigs); `load_sign` does the same for the stretch load.
Reading a recording into a link's data is the diagnosis's (teleop.diagnosis.links).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from teleop.core.physics.base import Signals, get_effect, moves

EXACT = 0.01          # a drive whose noise is below this fraction of its median per-sample move is exact


def noise_sigma(x: np.ndarray) -> float:
    """Robust standard deviation of the white noise on x [x's unit]: from its third differences (a motion
    sampled fast leaves almost nothing there, an operator's tremor included, which second differences took
    for noise; white noise of sigma gives 20 sigma^2), and at least the quantisation's q / sqrt(12) when x
    sits on a lattice of step q (an encoder's or a step counter's counts). Next to 0 for an exact signal (a
    commanded position)."""
    d3 = np.diff(x, 3)
    sigma = 1.4826 * float(np.median(np.abs(d3 - np.median(d3)))) / np.sqrt(20.0) if d3.size else 0.0
    steps = moves(x)
    if steps.size > 10:
        q = float(np.min(steps))
        if q > 0 and np.mean(np.abs(steps / q - np.round(steps / q)) < 0.01) > 0.95:
            sigma = max(sigma, q / np.sqrt(12.0))
    return sigma


def is_exact(x: np.ndarray) -> bool:
    """True for an exact drive (a commanded position, a noise-free simulation): its noise is below EXACT of
    its median per-sample move, so every reversal in it is motion (an operator's tremor reverses a command
    hundreds of times in 20 s, and a friction flips with each) and nothing is smoothed or thresholded."""
    steps = moves(x)
    return bool(steps.size) and noise_sigma(x) <= EXACT * float(np.median(steps))


@dataclass(frozen=True)
class Link:
    """kind: 'position' | 'force' | 'contact'; output, input, drive, load: recording channel names."""

    kind: str
    output: str
    input: str
    drive: str | None = None
    load: str | None = None

    @property
    def name(self) -> str:
        return f"{self.kind} link ({self.input} -> {self.output})"

    @property
    def spring_load(self) -> bool:
        """A force link whose load is a spring's travel (no tip force recorded): the load's zero is the
        spring's rest, which the recording does not give."""
        return self.kind == "force" and not self.input.endswith("force")

    @property
    def through_spring(self) -> bool:
        """A position link observed through a spring: its output is the tip force, F = g z + c with z the
        tip's travel; position effects act on z in the input's units, the gain is the spring's."""
        return self.kind == "position" and self.output.endswith("force")

    @property
    def effect_kinds(self) -> tuple:
        """Physics link kinds whose effects can be added on this link: a position link whose output is a
        force (the tip pulling a spring: the spring turns the tip's travel into force) also carries that
        force sensor's effects."""
        if self.kind == "position":
            return ("position", "sensor") if self.output.endswith("force") else ("position",)
        return {"force": ("force", "sensor"), "contact": ("contact", "sensor")}[self.kind]


@dataclass(frozen=True)
class LinkData:
    """A link's arrays: t (n,) [s], u (n,) input, y (n,) output, x (n,) smoothed drive or None, load,
    temperature, theta (bend angle) or None; resolution_s: the inputs' smoothing width [s] (the shortest
    time scale the data resolves)."""

    link: Link
    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    x: np.ndarray | None
    load: np.ndarray | None
    temperature: np.ndarray | None
    theta: np.ndarray | None
    resolution_s: float = 0.0
    known: dict = field(default_factory=dict)   # {effect: {param: value}} the user's simulation already knows
    backward: bool = False   # an exact drive's rate as the backward difference (clean_motion)
    v: np.ndarray | None = None   # the drive's rate, taken before decimation (an exact drive's reversals)
    cache: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def motion(self) -> tuple:
        """(x, v) of the drive as the link's effects see it (`clean_motion` on all samples; the given rate
        where there is one), or (None, None) without a drive (cached)."""
        if self.x is None:
            return None, None
        if self.v is not None:
            return self.x, self.v
        if "motion" not in self.cache:
            self.cache["motion"] = clean_motion(self.x, self.t, self.backward)
        return self.cache["motion"]

    def reversals(self) -> np.ndarray:
        """Sample indices where the drive's direction (sign of its rate, `motion`, held through rests) turns:
        the first sample moving the new way (cached; empty without a drive)."""
        if "reversals" not in self.cache:
            v = self.motion()[1]
            s = np.sign(v) if v is not None else np.zeros(0)
            k = np.flatnonzero(s)
            turn = k[1:][s[k[1:]] != s[k[:-1]]]
            self.cache["reversals"] = turn
        return self.cache["reversals"]

    def window(self, sl) -> "LinkData":
        """The samples `sl` (a decimating stride included, or an increasing index array). An exact drive's
        rate is taken on all samples first: a stride would step over the reversals of an operator's tremor,
        where a friction flips. On an index array every drive's motion is (`motion`)."""
        def cut(a):
            return None if a is None else a[sl]
        if isinstance(sl, np.ndarray):
            x, v = self.motion()
            return LinkData(self.link, self.t[sl], self.u[sl], self.y[sl], cut(x), cut(self.load),
                            cut(self.temperature), cut(self.theta), self.resolution_s, self.known, self.backward,
                            cut(v))
        v = self.v
        if v is None and self.x is not None and sl.step not in (None, 1):
            if "exact_rate" not in self.cache:   # once per LinkData: fits decimate it again and again
                self.cache["exact_rate"] = clean_motion(self.x, self.t, self.backward)[1] if is_exact(self.x) else None
            v = self.cache["exact_rate"]
        return LinkData(self.link, self.t[sl], self.u[sl], self.y[sl], cut(self.x), cut(self.load),
                        cut(self.temperature), cut(self.theta), self.resolution_s, self.known, self.backward, cut(v))


@dataclass(frozen=True)
class LinkModel:
    """Baseline gain g, offset c, direction (+1/-1), load_sign (+1/-1) and the effect chain
    ((name, {param: value}), ...) of one link; the first `base` effects belong to the baseline (the
    simulation the user already has, e.g. the sheath's capstan friction), the rest are findings."""

    link: Link
    gain: float
    offset: float
    direction: float = 1.0
    load_sign: float = 1.0
    effects: tuple = field(default=())
    base: int = 0

    def with_effects(self, effects) -> "LinkModel":
        effects = tuple(effects)
        names = [n for n, _ in effects]
        base = sum(1 for n in self.baseline_names if n in names)
        return LinkModel(self.link, self.gain, self.offset, self.direction, self.load_sign, effects, base)

    def without(self, names) -> "LinkModel":
        """This model with the effects `names` taken out (same gain and offset)."""
        return self.with_effects([(n, p) for n, p in self.effects if n not in names])

    @property
    def baseline_names(self) -> tuple:
        """Names of the baseline's effects."""
        return tuple(n for n, _ in self.effects[: self.base])

    def baseline_params(self) -> dict:
        return {"gain": self.gain, "offset": self.offset}


STOP_S = 0.05   # a quiet stretch (|v| within the noise) longer than this is a stop, not a reversal


def clean_motion(x: np.ndarray, t: np.ndarray, backward: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(x, v) of drive x with its rate's sign cleaned: where |v| is within the noise (3 sigma of the
    differentiated noise), a short quiet stretch (a reversal) keeps its direction up to its middle and
    switches there instead of flickering with the noise; a stretch longer than STOP_S is a stop: v = 0
    (sign(0) = 0, as the catalogue's rate laws define it) and x held, so that no state model integrates
    the sensor noise of a motor at rest. Magnitudes are kept elsewhere. An exact drive (`is_exact`) is
    taken as it is, every reversal in it motion; its rate is the central difference (the catalogue's array
    forms, teleop.core.physics Signals) or, with `backward`, the backward difference (the motion over the interval
    that ends at the sample, as a per-sample simulation such as the simulated robot's steps applies it): at a
    reversal they differ by one sample, and an operator's tremor reverses a command hundreds of times."""
    if x.size > 1 and is_exact(x):
        if not backward:
            return x, np.gradient(x, t)
        v = np.empty_like(x)
        v[1:] = np.diff(x) / np.diff(t)
        v[0] = v[1]
        return x, v
    v = np.gradient(x, t)
    # the rate's noise: x's own (third differences, `noise_sigma`) through the central difference; the
    # motion's fast content is not noise (a commanded position's jitter is motion)
    eps = 3.0 * noise_sigma(x) / float(np.median(np.diff(t)))
    s = np.where(v > eps, 1.0, np.where(v < -eps, -1.0, 0.0))
    n = s.size
    idx = np.where(s != 0, np.arange(n), 0)
    np.maximum.accumulate(idx, out=idx)
    fwd = np.where(s[idx] != 0, s[idx], 0.0)
    last_on = idx
    idx_b = np.where(s != 0, np.arange(n), n - 1)
    idx_b = np.minimum.accumulate(idx_b[::-1])[::-1]
    bwd = s[idx_b]
    k = np.arange(n)
    quiet = s == 0
    # inside a quiet stretch between last_on and next_on: first half forward sign, second half backward
    mid = 0.5 * (last_on + idx_b)
    sign = np.where(quiet, np.where((k <= mid) & (fwd != 0) | (bwd == 0), fwd, bwd), s)
    sign = np.where(sign == 0, bwd, sign)
    dt = float(np.median(np.diff(t)))
    stopped = quiet & ((idx_b - last_on) * dt > STOP_S) & (s[last_on] != 0) & (s[idx_b] != 0)
    sign = np.where(stopped, 0.0, sign)
    xc = np.where(stopped, x[last_on], x)
    return xc, sign * np.abs(v)


def fast_replace(sig: Signals, **changes) -> Signals:
    """A copy of `sig` with channels replaced by arrays already known to be valid (n,) floats; unlike
    Signals.replace nothing is re-checked or re-derived (the fitting loop calls this thousands of times)."""
    out = object.__new__(type(sig))   # a shallow copy, without the copy module's reduce protocol
    out.__dict__.update(sig.__dict__)
    out.__dict__.update(changes)
    return out


def _template(d: LinkData, m: LinkModel) -> Signals:
    """Checked Signals of the link for the model's direction and load sign, at unit gain (cached)."""
    key = (m.direction, m.load_sign)
    if key not in d.cache:
        kw = {"t": d.t}
        if d.x is not None:
            xc, vc = (d.x, d.v) if d.v is not None else clean_motion(d.x, d.t, d.backward)
            kw["x"] = m.direction * xc
            kw["v"] = m.direction * vc
        if d.temperature is not None:
            kw["temperature"] = d.temperature
        if d.theta is not None:
            kw["theta"] = d.theta
        if d.link.kind == "position":
            kw["x"] = d.u
            if d.load is not None:
                kw["load"] = m.load_sign * d.load
        elif d.link.kind == "force":
            kw["load"] = d.u
        else:
            kw["d"] = d.u
        d.cache[key] = Signals(**kw)
    return d.cache[key]


def effect_signals(d: LinkData, m: LinkModel) -> Signals:
    """The physics Signals the link's effects see (input referred through the baseline gain; through a
    spring the position effects see the input itself)."""
    sig = _template(d, m)
    if d.link.through_spring:
        return sig
    if d.link.kind == "position":
        return fast_replace(sig, x=m.gain * d.u + m.offset, v=m.gain * sig.v)
    if d.link.kind == "force":
        return fast_replace(sig, load=m.gain * d.u)
    return sig


def is_contact_law(name: str) -> bool:
    """True for a contact effect that is a force law of the indentation alone (linear, hertz)."""
    eff = get_effect(name)
    return eff.link == "contact" and tuple(eff.inputs) == ("d",)


def elastic_force(d: LinkData, m: LinkModel, sig: Signals | None = None) -> np.ndarray:
    """Contact link: the elastic law's force (n,): a catalogue law in m's chain (hertz) replaces the
    baseline's linear one, gain * max(d, 0)."""
    sig = effect_signals(d, m) if sig is None else sig
    for name, p in m.effects:
        if is_contact_law(name):
            return get_effect(name).apply(sig, p)
    return m.gain * np.maximum(d.u, 0.0)


STAGES = 48   # predict's memo: the stage outputs kept per LinkData (least recently used dropped)


def _stage(d: LinkData, key, run):
    """run() (a tuple of arrays), memoised in d.cache under `key` (hashable: the chain up to this stage and
    what enters it). A fit's finite-difference Jacobian moves one parameter at a time, and the chain's
    stages before that parameter's effect see the same inputs: their outputs are taken from the memo, bit
    for bit what run() would give (kept read-only, so no caller can change them)."""
    memo = d.cache.get("stages")
    if memo is None:
        memo = d.cache["stages"] = OrderedDict()
    try:
        out = memo.get(key)
    except TypeError:   # a parameter value that is not hashable: not memoised
        return run()
    if out is not None:
        memo.move_to_end(key)
        return out
    out = run()
    for a in out:
        if isinstance(a, np.ndarray):
            a.flags.writeable = False
    memo[key] = out
    if len(memo) > STAGES:
        memo.popitem(last=False)
    return out


def _apply(name: str, sig: Signals, p: dict) -> tuple:
    return (get_effect(name).apply(sig, p),)


def predict(d: LinkData, m: LinkModel) -> np.ndarray:
    """The link's output (n,) under model `m` (baseline plus its effect chain). The effects' outputs are
    memoised per link data (`_stage`): the key is what each stage's output depends on (the referred
    input's gain and offset where they enter it, direction, load sign, and each effect's name and
    parameters up to it)."""
    sig = effect_signals(d, m)
    kind = d.link.kind
    sensor = [(n, p) for n, p in m.effects if get_effect(n).link == "sensor"]
    chain = [(n, p) for n, p in m.effects if get_effect(n).link != "sensor"]
    key = (kind, m.direction, m.load_sign)
    if kind == "position":
        if not d.link.through_spring:
            key += (m.gain, m.offset)
        z = sig.x
        for i, (name, p) in enumerate(chain):
            # as Signals.replace, unchecked; the rate is derived only where a later effect reads it (the
            # fitting loop runs this tens of thousands of times)
            later = {c for n, _ in chain[i + 1:] for c in get_effect(n).inputs + get_effect(n).optional}
            key = (key, name, tuple(p.items()), "v" in later)

            def run(sig=sig, name=name, p=p, rate="v" in later):
                z = get_effect(name).apply(sig, p)
                return z, (np.gradient(z, sig.t) if rate else None)
            z, v = _stage(d, key, run)
            sig = fast_replace(sig, x=z, v=v)
        y = m.gain * z + m.offset if d.link.through_spring else z
        key = (key, m.gain, m.offset)
    elif kind == "force":
        key += (m.gain,)
        z = sig.load
        for name, p in chain:
            key = (key, name, tuple(p.items()))
            z, = _stage(d, key, lambda sig=sig, name=name, p=p: _apply(name, sig, p))
            sig = fast_replace(sig, load=z)
        y = z + m.offset
        key = (key, m.offset)
    else:
        y = elastic_force(d, m, sig)
        for name, p in chain:
            if not is_contact_law(name):
                y = get_effect(name).apply(fast_replace(sig, force=y), p)
        y = y + m.offset
        key = None
    for name, p in sensor:
        sig = fast_replace(sig, force=y)
        if key is None:
            y = get_effect(name).apply(sig, p)
        else:
            key = (key, name, tuple(p.items()))
            y, = _stage(d, key, lambda sig=sig, name=name, p=p: _apply(name, sig, p))
    return y if y.flags.writeable else y.copy()   # the caller's own array, never the memo's
