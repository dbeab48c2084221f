"""The pieces every effect is made of: named signals, parameter specs, the Effect record and the registry.

- `Signals`: a frozen bundle of equal-length 1-D arrays over time (SI units), the input of every effect.
- `ParamSpec`: one parameter's name, unit, fit bounds, typical value and meaning.
- `Effect`: one model = its per-sample physics, one compiled step kernel (`Kernel`; the array form
  `simulate(signals, params) -> (n,)` is the one driver's loop over it, the real-time `Step` calls it per
  sample), a `guess(signals, y) -> params` for fitting, and its parameter specs.
- `Rules`: what the diagnosis, the generators and the docs read of an effect (link channel, primary
  parameters, what it cannot be told apart from, its fit starts, its generator draw).
- `REGISTRY` / `get_effect(name)`: the catalogue by canonical name.

Parameters travel as plain ``{name: float}`` dicts so they map one-to-one to JSON and to fit vectors.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from teleop.core.errors import InputError

#: channel name -> meaning and unit; every Signals field except t is optional.
CHANNELS: dict[str, str] = {
    "t": "time [s]",
    "x": "input (motor, proximal) position [m or rad]; increasing x = the motor hauls the cable in (pulling)",
    "v": "velocity of x [m/s or rad/s]; derived from x by central differences when not given",
    "load": "distal (tip) force [N or N m]",
    "force": "a force channel the effect modifies (sensor reading, contact force) [N or N m]",
    "temperature": "temperature at the sensor [degC]",
    "theta": "accumulated sheath bend angle along the cable route [rad]",
    "d": "contact indentation [m]; d <= 0 means no contact",
    "d_dot": "indentation rate [m/s]; derived from d when not given",
}

LINKS = ("position", "force", "sensor", "contact")


@dataclass(frozen=True, eq=False)
class Signals:
    """Equal-length (n,) float arrays over time. Missing channels are None.

    `v` is derived from `x`, and `d_dot` from `d`, with `np.gradient` (central differences) when absent.
    """

    t: np.ndarray
    x: np.ndarray | None = None
    v: np.ndarray | None = None
    load: np.ndarray | None = None
    force: np.ndarray | None = None
    temperature: np.ndarray | None = None
    theta: np.ndarray | None = None
    d: np.ndarray | None = None
    d_dot: np.ndarray | None = None

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise InputError(f"signals: 't' must be a 1-D array of at least 2 samples, got shape {t.shape}")
        if not np.isfinite(t).all() or np.any(np.diff(t) <= 0):
            raise InputError("signals: 't' must be finite and strictly increasing")
        object.__setattr__(self, "t", t)
        for name in CHANNELS:
            if name == "t":
                continue
            a = getattr(self, name)
            if a is None:
                continue
            a = np.asarray(a, dtype=float)
            if a.ndim == 0:
                a = np.full(t.shape, float(a))
            if a.shape != t.shape:
                raise InputError(f"signals: channel '{name}' has shape {a.shape}, expected {t.shape} like 't'")
            if not np.isfinite(a).all():
                raise InputError(f"signals: channel '{name}' holds NaN or inf")
            object.__setattr__(self, name, a)
        if self.x is not None and self.v is None:
            object.__setattr__(self, "v", np.gradient(self.x, t))
        if self.d is not None and self.d_dot is None:
            object.__setattr__(self, "d_dot", np.gradient(self.d, t))

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    def __getitem__(self, name: str) -> np.ndarray | None:
        if name not in CHANNELS:
            raise KeyError(name)
        return getattr(self, name)

    def channels(self) -> tuple[str, ...]:
        """Names of the channels present."""
        return tuple(c for c in CHANNELS if getattr(self, c) is not None)

    def replace(self, **changes) -> "Signals":
        """A copy with channels replaced; replacing x (or d) without v (or d_dot) re-derives the rate."""
        if "x" in changes and "v" not in changes:
            changes["v"] = None
        if "d" in changes and "d_dot" not in changes:
            changes["d_dot"] = None
        return dataclasses.replace(self, **changes)

    def window(self, index) -> "Signals":
        """Samples `index` (slice or index array) of every channel."""
        kw = {c: getattr(self, c)[index] for c in self.channels()}
        return Signals(**kw)

    def require(self, names, who: str) -> None:
        """Raise InputError naming `who` and the first missing channel."""
        for name in names:
            if getattr(self, name) is None:
                raise InputError(f"{who}: needs signal channel '{name}' ({CHANNELS[name]})")


@dataclass(frozen=True)
class ParamSpec:
    """One model parameter: SI unit, fit bounds [lower, upper], a typical value, and its meaning.

    `log=True` fits it on a log scale (for quantities spanning decades; then lower > 0), or, with `tiny` > 0,
    a signed quantity spanning decades (lower < 0 < upper) on asinh(value / tiny): linear within +-tiny,
    logarithmic beyond, either sign (a stiffness that may be negative).
    Values given to an effect must be >= 0 when lower >= 0, and > 0 when `positive` (a divisor).
    `shape=True`: a parameter of the effect's general form whose default is the plain form (backlash's
    elastic part, wide play, growth and start): fits hold it at its default unless asked to free it.
    `state=True`: an initial state of the record, not a property of the link (where a play began in its
    band): fitted on every recording (never carried from one to another), and a value on a bound is a
    state the data can hold, not a sign that the effect's form is wrong.
    `alone=True`: a shape parameter the general form keeps only where it pays on its own (the general form
    refitted with it held at its default is worse by the diagnosis' parsimony margin): one whose physics
    needs a load the record may not carry (backlash's growth with a spring's tension).
    """

    name: str
    unit: str
    lower: float
    upper: float
    default: float
    doc: str
    log: bool = False
    positive: bool = False
    shape: bool = False
    state: bool = False
    tiny: float = 0.0
    alone: bool = False

    def __post_init__(self):
        signed = self.log and self.tiny > 0
        if not self.lower < self.upper or (self.log and not signed and self.lower <= 0) or (
                signed and not self.lower < 0 < self.upper):
            raise ValueError(f"ParamSpec {self.name}: bad bounds [{self.lower}, {self.upper}]")

    def _scale(self, value: float) -> float:
        """The fit's coordinate of `value`: log, asinh(value / tiny) (signed log) or the value itself."""
        if self.log:
            return math.asinh(value / self.tiny) if self.tiny > 0 else math.log(value)
        return value

    def to_unit(self, value: float) -> float:
        """Map a value in [lower, upper] to [0, 1] (linearly, in log or in signed log)."""
        lo, hi = self._scale(self.lower), self._scale(self.upper)
        return (self._scale(value) - lo) / (hi - lo)

    def from_unit(self, u: float) -> float:
        """Inverse of `to_unit`."""
        lo, hi = self._scale(self.lower), self._scale(self.upper)
        z = lo + u * (hi - lo)
        if self.log:
            return self.tiny * math.sinh(z) if self.tiny > 0 else math.exp(z)
        return z

    def dvalue_du(self, value: float) -> float:
        """d value / d u at `value` (for standard errors)."""
        span = self._scale(self.upper) - self._scale(self.lower)
        if self.log:
            return (math.hypot(self.tiny, value) if self.tiny > 0 else value) * span
        return span

    def clip(self, value: float) -> float:
        """`value` clipped into [lower, upper]."""
        return float(min(max(value, self.lower), self.upper))


class Step(ABC):
    """Per-sample (real-time) form of an effect: same math as the array form, state held here.

    Subclasses set `effect_name`, implement `reset()` and `step(<channels>) -> float` whose keyword names
    are the effect's input channels (e.g. `BacklashStep.step(x)`), and read parameters from
    `self.params`. The first `step` call initialises the state exactly as the array form does.
    """

    effect_name: str = ""
    _effect: "Effect | None" = None  # set for effects outside the registry (chains)

    def __init__(self, params: Mapping[str, float] | None = None):
        effect = type(self)._effect or get_effect(self.effect_name)
        self.params = effect.check(params)
        self.reset()

    @abstractmethod
    def reset(self) -> None:
        """Forget the state; the next `step` starts afresh."""

    @abstractmethod
    def step(self, **u) -> float:
        """Advance one sample and return the output channel's value."""


@dataclass(frozen=True)
class Kernel:
    """An effect's per-sample physics, written once: `step(s, u, p) -> y`, a compiled kernel of
    teleop.core.kernels.effects (its docstring: s the state, u one sample of the channels Effect.inputs +
    Effect.optional, p the parameters), and `run(s, U, p, out)` the compiled loop of that step along U (n, k).
    state: s before the first sample (NaN first: the step starts it from that sample); pack(params) -> p
    (default: the values in the ParamSpecs' order)."""

    step: Callable
    run: Callable
    state: tuple[float, ...] = (math.nan,)
    pack: Callable[[Mapping[str, float]], tuple] | None = None


class KernelStep(Step):
    """Per-sample form of an effect with a `Kernel`: step(**channels) calls its step kernel once; run(**arrays)
    is its array form from this state. The state (`state`, the kernel's s) is left at the last sample."""

    def reset(self) -> None:
        eff = self.effect()
        self.state = np.array(eff.kernel.state, dtype=float)
        self._p = eff.packed(self.params)
        self._names = eff.inputs + eff.optional
        self._row = np.empty(len(self._names))   # one sample of the channels, refilled by each step
        self._step = eff.kernel.step

    @classmethod
    def effect(cls) -> "Effect":
        return cls._effect or get_effect(cls.effect_name)

    def step(self, **u) -> float:
        row = self._row
        for j, c in enumerate(self._names):
            row[j] = self._channel(c, u.get(c))
        return float(self._step(self.state, row, self._p))

    def run(self, **arrays) -> np.ndarray:
        """(n,) the output along (n,) arrays of the channels (the array form), continuing from this state."""
        cols = [np.broadcast_to(np.asarray(self._channel(c, arrays.get(c)), dtype=float),
                                np.shape(arrays[self._names[0]])) for c in self._names]
        return drive_kernel(self.effect().kernel, self.state, np.column_stack(cols), self._p)

    def _channel(self, name: str, value):
        if value is not None:
            return value
        if name in self.params:   # an optional channel not given: the parameter of its name
            return self.params[name]
        raise InputError(f"effect '{self.effect_name}': step needs channel '{name}'")


def drive_kernel(kernel: Kernel, state: np.ndarray, U: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(n,) kernel.step along the samples U (n, k) from state (updated in place to the last sample's)."""
    U = np.ascontiguousarray(U, dtype=float)
    return kernel.run(state, U, np.ascontiguousarray(p, dtype=float), np.empty(U.shape[0]))


def kernel_call(kernel: Kernel, p, *channels, state=None):
    """kernel.step along the channels (arrays broadcast against each other, samples along the flattened
    broadcast shape) under the parameter vector p, from `state` (default: the kernel's start); the result
    has the broadcast shape."""
    arrs = np.broadcast_arrays(*[np.asarray(c, dtype=float) for c in channels])
    U = np.column_stack([a.reshape(-1) for a in arrs])
    s = np.array(kernel.state, dtype=float) if state is None else state
    return drive_kernel(kernel, s, U, np.asarray(p, dtype=float)).reshape(arrs[0].shape)


@dataclass(frozen=True, eq=False)
class LinkRecord:
    """What an effect's diagnosis rules read of one link's recording: (n,) arrays in SI units, None where
    the channel is not recorded. u, y: the link's input and output; x: the drive position; tip: the tip's
    travel (the link's output, or its input where the tip is read through a spring); resolution_s [s]: the
    shortest time scale the inputs resolve; load: the link's load channel (a position link's tip force),
    None where it has none."""

    u: np.ndarray
    y: np.ndarray
    x: np.ndarray | None
    theta: np.ndarray | None
    temperature: np.ndarray | None
    tip: np.ndarray
    resolution_s: float = 0.0
    load: np.ndarray | None = None


def moves(x: np.ndarray) -> np.ndarray:
    """|x_k+1 - x_k| of the samples where x moves at all (drive_step, and the links' noise_sigma, is_exact)."""
    dx = np.abs(np.diff(x))
    return dx[dx > 1e-12 * max(float(np.max(np.abs(x))), 1e-300)] if dx.size else dx


def drive_step(x: np.ndarray) -> float:
    """The drive's typical travel [its unit] in one sample: the median per-sample move while moving."""
    moving = moves(x)
    return float(np.median(moving)) if moving.size else 0.0


@dataclass(frozen=True)
class Scale:
    """The magnitudes a generator draws an effect's parameters against (SI): the drive's half travel
    [m], the tip load's mean and span [N], the rig's friction level [N] (drawn once per recording), fast
    and slow drive speeds [m/s] (99th and 25th percentiles of |v| while moving; indentation rates on a
    pad), the span of the force a sensor reads [N] and of the temperature [K], and a pad's linear
    stiffness [N/m]."""

    travel: float = 0.0
    load: float = 0.0
    load_span: float = 0.0
    friction: float = 0.0
    v_fast: float = 0.0
    v_slow: float = 0.0
    force_span: float = 0.0
    temp_span: float = 0.0
    stiffness: float = 0.0


@dataclass(frozen=True)
class Rules:
    """An effect's own rules, read by the diagnosis, the generators, the benches and the docs (the catalogue
    is extended by registering an effect with its rules, in its own module).

    channel: the recording channel the effect shows on in a generated rig ("tip_pos", "motor_force",
    "force"; a sensor effect: the sensor it sits on by default).
    primary: the parameters a diagnosis is scored on (the others are nuisance or shape parameters).
    alike: effects it cannot be told apart from on one channel where the load follows the drive (a
    spring-loaded tip: loading and pulling coincide); generators do not conceal the two together.
    not_beside: baseline effects whose law it is by another name on the data a link carries: beside one of
    them in the baseline it is not a candidate.
    finding: False for a law that is only ever a baseline, or a change with no physical cause to name.
    position_only: a function of the drive position alone (told apart from a load that follows the
    position, and from a periodic force, by its shape only).
    periodic: its contribution is itself periodic in the drive position (a transmission error): the
    diagnosis does not hold that location against it as physics outside the catalogue.
    starts: fit starts when the effect is added (parameters with basins of their own).
    gain_restarts: factors on the baseline gain to refit from when it is the first effect of its own link
    (an effect that flattens the affine gain, as a wide play does).
    hold(record, known, direction) -> {param: value}: parameters held fixed in a fit (those identifiable
    only as a product or sum with another, and record-relative references); `known` the parameters the
    user's simulation already has, `direction` +-1 the link's pulling direction.
    wrong_form(params, record) -> True when fitted values contradict the effect's defining signature.
    baseline_starts(record, index, gain, offset, direction) -> [(direction, gain, offset, params)]: extra
    starts when the effect is in a baseline (`index` the fit part's sample indices).
    draw(rng, scale) -> params: a generator's random parameters, material but not dominant.
    baseline: part of the project's simulation of a cable setup (the diagnosis's default baseline).
    rate_probe: the simplest law of the drive's rate: the diagnosis fits it to tell which rate convention
    (central or backward differences) an exact drive's recording prefers.
    raw_input: its signature is sharp in the input (a play's take-up): found on a position link whose input
    the diagnosis smooths, the link is identified on its raw input too and the better kept.
    input_units: parameters in the output's unit that the diagnosis also reports in the input's (divided by
    the link's gain).
    reading: its contribution to a link's output may be the output sensor's own (a late reading: a lag):
    found there, a later link that reads the channel as its input is offered the channel without it, as
    it is a sensor effect's (kept where that link's baseline fits better with it).
    also_known_as: names a generator gives this physics when it writes it itself, outside the catalogue (the
    single-cable rig's late tip-force sensor, "sensor_delay", is a transport_delay): a bench scores a finding
    of this effect as the right answer for them (the generator's truth carries this effect's parameters).
    extends: a simpler catalogue effect that is this one's special case (its parameters a subset of this
    one's, by name): where both are candidates, this one is also fitted from the other's fitted chain, so
    that its extra parameters start where the simpler law ends (a fit from its own guess can end in a
    basin worse than the simpler law it contains), and it is named only where they pay on held-out data.
    nested_starts(params, signals) -> [params]: the starts of that fit, from the simpler effect's fitted
    parameters and the signals the effect reads (Signals: v, load).
    general_candidate: its general form (ParamSpec.shape) is a candidate of its own beside the plain one,
    not only a refinement once the plain form is named (a stretch under a load read beyond the sheath's
    friction: the plain form cannot pay there)."""

    channel: str = ""
    primary: tuple[str, ...] = ()
    alike: tuple[str, ...] = ()
    not_beside: tuple[str, ...] = ()
    finding: bool = True
    position_only: bool = False
    periodic: bool = False
    starts: int = 1
    gain_restarts: tuple[float, ...] = ()
    hold: Callable[[LinkRecord, Mapping[str, float], float], dict] | None = None
    wrong_form: Callable[[Mapping[str, float], LinkRecord], bool] | None = None
    baseline_starts: Callable[..., list] | None = None
    draw: Callable[[np.random.Generator, Scale], dict] | None = None
    baseline: bool = False
    rate_probe: bool = False
    raw_input: bool = False
    input_units: tuple[str, ...] = ()
    reading: bool = False
    also_known_as: tuple[str, ...] = ()
    extends: str = ""
    nested_starts: Callable[[Mapping[str, float], Signals], list] | None = None
    general_candidate: bool = False


@dataclass(frozen=True)
class Effect:
    """One named model of the catalogue.

    name: canonical name (registry key); link: 'position' | 'force' | 'sensor' | 'contact';
    inputs: channels `simulate` and `Step.step` need; optional: channels used when present (for a kernel,
    a parameter of the same name stands in for a missing one);
    output: the channel the result stands for (chaining writes it back there);
    kernel: the per-sample physics (`Kernel`); with it, simulate and step_class default to the driver's loop
    over it and `KernelStep`. Without one (an effect written in Python, a chain): simulate(signals, params)
    -> (n,) array and step_class, a Step subclass. guess(signals, y) -> params dict;
    rules: what the diagnosis, the generators and the docs read of it (`Rules`).
    """

    name: str
    link: str
    doc: str
    params: tuple[ParamSpec, ...]
    inputs: tuple[str, ...]
    output: str
    guess: Callable[[Signals, np.ndarray], dict]
    simulate: Callable[[Signals, Mapping[str, float]], np.ndarray] | None = None
    step_class: type | None = None
    optional: tuple[str, ...] = field(default=())
    rules: Rules = field(default=Rules())
    kernel: Kernel | None = None

    def __post_init__(self):
        if self.kernel is None:
            if self.simulate is None or self.step_class is None:
                raise ValueError(f"effect '{self.name}': needs a kernel, or simulate and step_class")
            return
        missing = [c for c in self.optional if c not in self.param_names]
        if missing:
            raise ValueError(f"effect '{self.name}': optional channels {missing} have no parameter to stand in")
        if self.simulate is None:
            object.__setattr__(self, "simulate", lambda signals, params: self.run(signals, params))
        if self.step_class is None:
            object.__setattr__(self, "step_class", type(f"{self.name}_step", (KernelStep,),
                                                        {"effect_name": self.name, "_effect": self}))

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    def packed(self, params: Mapping[str, float]) -> np.ndarray:
        """The kernel's parameter vector p of the full `params` (Kernel.pack, or the ParamSpecs' order)."""
        k = self.kernel
        vals = k.pack(params) if k.pack is not None else [params[n] for n in self.param_names]
        return np.array(vals, dtype=float)

    def run(self, signals: Signals, params: Mapping[str, float], state: np.ndarray | None = None) -> np.ndarray:
        """(n,) the kernel's array form: its step along every sample of `signals` under the full `params`,
        from `state` (default: the kernel's start; a given state is left at the last sample's)."""
        n = signals.n
        cols = [signals[c] if signals[c] is not None else np.full(n, float(params[c]))
                for c in self.inputs + self.optional]
        s = np.array(self.kernel.state, dtype=float) if state is None else state
        return drive_kernel(self.kernel, s, np.column_stack(cols), self.packed(params))

    def spec(self, name: str) -> ParamSpec:
        """The ParamSpec called `name`."""
        for p in self.params:
            if p.name == name:
                return p
        raise InputError(f"effect '{self.name}': unknown parameter '{name}' (expected {list(self.param_names)})")

    def defaults(self) -> dict:
        """Typical parameter values."""
        return {p.name: p.default for p in self.params}

    def plain_form(self) -> dict:
        """{name: default} of the general form's parameters (ParamSpec.shape): held there, the plain form."""
        return {p.name: p.default for p in self.params if p.shape}

    def check(self, params: Mapping[str, float] | None) -> dict:
        """A full, validated {name: float} dict: missing names take defaults, unknown names raise."""
        out = self.defaults()
        if params is None:
            return out
        for k, v in dict(params).items():
            if k not in out:
                raise InputError(f"effect '{self.name}': unknown parameter '{k}' "
                                 f"(expected {list(self.param_names)})")
            v = float(v)
            spec = self.spec(k)
            if not math.isfinite(v) or (spec.positive and v <= 0) or (spec.lower >= 0 and v < 0):
                need = "> 0" if spec.positive else (">= 0" if spec.lower >= 0 else "finite")
                raise InputError(f"effect '{self.name}': parameter '{k}' must be {need}, got {v}")
            out[k] = v
        return out

    def apply(self, signals: Signals, params: Mapping[str, float] | None = None) -> np.ndarray:
        """The output channel (n,) for `signals` under `params` (defaults where missing)."""
        signals.require(self.inputs, f"effect '{self.name}'")
        return self.simulate(signals, self.check(params))

    def describe(self) -> dict:
        """JSON-ready summary: name, link, doc, inputs, output and each parameter's unit, bounds, default."""
        return {"name": self.name, "link": self.link, "doc": self.doc, "inputs": list(self.inputs),
                "optional": list(self.optional), "output": self.output,
                "params": {p.name: {"unit": p.unit, "lower": p.lower, "upper": p.upper, "default": p.default,
                                    "log": p.log, "doc": p.doc} for p in self.params}}

    def make_step(self, params: Mapping[str, float] | None = None) -> Step:
        """A fresh per-sample simulator with these parameters."""
        return self.step_class(params)

    def initial_guess(self, signals: Signals, y: np.ndarray) -> dict:
        """Data-driven starting point for a fit, clipped into the bounds."""
        g = self.check(self.guess(signals, np.asarray(y, dtype=float)))
        return {p.name: p.clip(g[p.name]) for p in self.params}


REGISTRY: dict[str, Effect] = {}


def register(effect: Effect) -> Effect:
    """Add `effect` to REGISTRY under its name (once) and return it."""
    if effect.name in REGISTRY:
        raise ValueError(f"effect '{effect.name}' registered twice")
    if effect.link not in LINKS:
        raise ValueError(f"effect '{effect.name}': link must be one of {LINKS}")
    unknown = [p for p in effect.rules.primary if p not in effect.param_names]
    if unknown:
        raise ValueError(f"effect '{effect.name}': primary parameters {unknown} are not among its parameters")
    REGISTRY[effect.name] = effect
    return effect


def unregister(name: str) -> None:
    """Take effect `name` out of REGISTRY (a throwaway effect registered by a test)."""
    REGISTRY.pop(name, None)


def alike(a: str, b: str) -> bool:
    """True when registered effects `a` and `b` cannot be told apart (either lists the other in Rules.alike)."""
    return b in get_effect(a).rules.alike or a in get_effect(b).rules.alike


def get_effect(name: str) -> Effect:
    """The registered effect called `name`; InputError listing the known names otherwise."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise InputError(f"unknown effect '{name}' (known: {', '.join(sorted(REGISTRY))})") from None


def chain(*effects: "Effect | str", name: str | None = None) -> Effect:
    """One effect applying `effects` in order, each one's output written into its `output` channel for the
    next (e.g. chain("linear_contact", "viscoelasticity", "contact_damping"), or capstan then coulomb).

    Parameters are namespaced "<effect>.<param>"; inputs are the channels no earlier effect produces.
    Channels are replaced as they are (rates such as v are not re-derived), identically in the Step form.
    The guess uses defaults for all but the last effect. Not registered.
    """
    effs = tuple(get_effect(e) if isinstance(e, str) else e for e in effects)
    if not effs or len({e.name for e in effs}) != len(effs):
        raise InputError("chain: needs one or more distinct effects")
    cname = name or "+".join(e.name for e in effs)
    params = tuple(dataclasses.replace(p, name=f"{e.name}.{p.name}") for e in effs for p in e.params)
    produced: set[str] = set()
    inputs: list[str] = []
    optional: list[str] = []
    for e in effs:
        inputs += [c for c in e.inputs if c not in produced and c not in inputs]
        optional += [c for c in e.optional if c not in produced and c not in optional]
        produced.add(e.output)

    def split(p: Mapping[str, float]) -> list[dict]:
        return [{k.split(".", 1)[1]: v for k, v in p.items() if k.split(".", 1)[0] == e.name} for e in effs]

    def simulate(s: Signals, p: Mapping[str, float]) -> np.ndarray:
        for e, sub in zip(effs, split(p)):
            y = e.simulate(s, sub)
            s = dataclasses.replace(s, **{e.output: y})
        return y

    def guess(s: Signals, y: np.ndarray) -> dict:
        out = {}
        for e in effs[:-1]:
            out.update({f"{e.name}.{k}": v for k, v in e.defaults().items()})
            s = dataclasses.replace(s, **{e.output: e.simulate(s, e.defaults())})
        out.update({f"{effs[-1].name}.{k}": v for k, v in effs[-1].initial_guess(s, y).items()})
        return out

    class ChainStep(Step):
        """Per-sample chain: step(**channels) -> the last effect's output."""

        def reset(self) -> None:
            self.steps = [e.make_step(sub) for e, sub in zip(effs, split(self.params))]

        def step(self, **u) -> float:
            for e, st in zip(effs, self.steps):
                y = st.step(**{c: u[c] for c in e.inputs + e.optional if c in u and u[c] is not None})
                u[e.output] = y
            return y

    eff = Effect(name=cname, link=effs[-1].link, doc=" then ".join(e.doc for e in effs), params=params,
                 inputs=tuple(inputs), output=effs[-1].output, simulate=simulate, guess=guess,
                 step_class=ChainStep, optional=tuple(optional))
    ChainStep._effect = eff
    ChainStep.effect_name = cname
    return eff

