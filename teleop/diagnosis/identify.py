"""Name the missing physics: fit catalogue effects on top of a link's baseline and rank them on held-out data.

For each link: the baseline (gain, offset, and the baseline effects the simulation already has, e.g. the
sheath's capstan friction: `simulation_baseline`) is fitted on the first part of the recording (`fit`), every
other catalogue effect that the link's channels allow is fitted jointly with it (scipy least_squares,
parameters in the physics registry's bounded unit space), and all are scored by RMSE on the last part
(`hold`), with the model run over the whole record so stateful effects carry their history. An effect is
accepted when it lowers the held-out RMSE by at least ACCEPT and its information criterion (BIC with
the residual's effective sample count, residuals being autocorrelated) improves; among candidates whose
held-out RMSE is within PARSIMONY of the best, the one with the fewest parameters wins. Effects are added
greedily while they pay. An effect whose own contribution is best located where no catalogue effect acts
(FOREIGN: periodic in position) is not named; when no single effect pays, pairs of the PAIR_TOP best are
fitted jointly (`_pair`); a pure delay that fits better than any effect names nothing (`delay_fit`). A
chain whose held-out RMSE is within ACCEPT of its residual's white noise (locate.noise_level) takes no
addition, and pairs are tried only above ACCEPT^2 of it: nothing fits below the noise, so none could pay.
Fits run on the fit part decimated, with the samples about each of the drive's reversals (`fit_samples`).
An added effect's general form (ParamSpec.shape) is tried once it is named (`general_form`); the baseline's
own, in place of the additions once they are exhausted (`_general_baseline`: the capstan's pretension). A
baseline shape parameter that must pay on its own (ParamSpec.alone: the curve of the capstan's stick
transitions) is the baseline's choice, made on the baseline alone (`_baseline_shape`), never a finding.
The fit part is scored with Huber's loss (`robust_rms`) for the information criterion; held-out scores are
plain RMSEs.
An effect that extends a simpler one (Rules.extends: a Stribeck friction a Coulomb one) is also fitted from
the simpler one's candidate fit (`_nested`), its extra parameters at the rule's starts.
Every effect-specific rule (which effects are never findings, what a fit holds, extra starts, a form the
fitted values contradict, a baseline effect beside which an effect is no candidate, effects of the drive
position alone) is the effect's own (teleop.core.physics.base.Rules), read here through `record(d)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from teleop.core.fit_statistics import parameter_covariance, residual_variance
from teleop.core.physics.links import (LinkData, LinkModel, effect_signals, fast_replace, is_contact_law,
                                      predict)
from teleop.diagnosis.links import fit_baseline
from teleop.diagnosis.locate import locate, noise_level, periodic_features, r2, travel_phase
from teleop.core.physics import REGISTRY, get_effect
from teleop.core.physics.base import LinkRecord

ACCEPT = 1.20        # held-out RMSE must fall by >= 20 % for an effect to be named
ROUND_OFF_SHARE = 1e-12  # of a channel's range (scoring.ROUND_OFF is absolute): a residual below it is the float's
                         # round-off (an exact encoder's tip following an exact motor), where a free-period map or
                         # any flexible law fits nothing real
PARSIMONY = 0.08     # candidates within 8 % of the best held-out RMSE count as equally good (a
                     # discontinuous model's switching time is noise-limited: smoother relatives win a
                     # few per cent at reversals without being the physics)
MAX_EFFECTS = 3      # per link
NEAR_FLOOR = 1.15    # an addition that ends within this factor of the residual's white noise ...
NEAR_ACCEPT = math.sqrt(ACCEPT)   # ... pays from this held-out improvement on (`_pays`)
FIT_SAMPLES = 2000   # fits run on the fit part decimated to about this many samples (stateful effects
                     # integrate along the smoothed drive, exact on monotone stretches); scores use all
MIN_FIT_RATE_DT = 0.01  # ... but never decimated below 100 Hz (reversal timing), so long records fit more


def record(d: LinkData) -> LinkRecord:
    """What an effect's rules (physics Rules) read of link data d."""
    return LinkRecord(d.u, d.y, d.x, d.theta, d.temperature, d.u if d.link.through_spring else d.y, d.resolution_s,
                      d.load)


def fixed_params(d: LinkData, name: str, general: bool = False, direction: float = 1.0) -> dict:
    """Parameters held fixed when fitting `name` on link data d: the effect's own (Rules.hold: those
    identifiable only as a product or sum with another, references counted from the record), the
    parameters of the effect's general form at their plain defaults (ParamSpec.shape) unless `general`,
    and those the recording's metadata says the user's simulation already has (`LinkData.known`)."""
    eff = get_effect(name)
    known = d.known.get(name, {})
    out = {} if general else eff.plain_form()
    if eff.rules.hold is not None:
        out.update(eff.rules.hold(record(d), known, direction))
    return {**out, **known}


def fit_samples(d: LinkData, fit_idx: slice, dt: float) -> slice | np.ndarray:
    """The samples a fit runs on: the fit part decimated (FIT_SAMPLES, MIN_FIT_RATE_DT), and the two samples
    about each of the drive's reversals (a slice where that adds nothing). A decimated step across a
    reversal would hide where the direction turned, which a friction's switch and a stick's travel since the
    turn depend on to the sample, and the parameters fitted on it would be those of a later switch."""
    start, stop = fit_idx.start or 0, fit_idx.stop
    stride = max(1, min((stop - start) // FIT_SAMPLES, int(MIN_FIT_RATE_DT / dt)))
    if stride == 1 or d.x is None:
        return slice(start, stop, stride)
    rev = d.reversals()
    rev = rev[(rev >= start) & (rev < stop)]
    if rev.size == 0:
        return slice(start, stop, stride)
    if 2 * rev.size > MAX_REVERSAL_SAMPLES:   # a tremor's hundreds of turns: the widest apart
        rev = np.sort(rev[np.argsort(-np.diff(np.r_[start, rev]), kind="stable")[: MAX_REVERSAL_SAMPLES // 2]])
    keep = np.zeros(stop - start, dtype=bool)
    keep[::stride] = True
    for off in (-1, 0):   # the last sample before the turn and the first after: no step spans it
        k = rev - start + off
        keep[k[(k >= 0) & (k < keep.size)]] = True
    return np.flatnonzero(keep) + start


def sample_weights(idx: np.ndarray) -> np.ndarray:
    """(m,) the samples of record each of the increasing indices idx stands for (half the gaps to its
    neighbours, a whole gap at the ends)."""
    gaps = np.diff(idx).astype(float)
    if not gaps.size:
        return np.ones(idx.size)
    return 0.5 * (np.r_[gaps[0], gaps] + np.r_[gaps, gaps[-1]])


MAX_REVERSAL_SAMPLES = FIT_SAMPLES // 2   # at most this many samples added about reversals


@dataclass(frozen=True)
class Fit:
    """One fitted chain: model, standard errors {effect: {param: se}}, RMSE on fit and held-out samples,
    free-parameter count k, effective sample count n_eff of the fit residual."""

    model: LinkModel
    stderr: dict
    rmse_fit: float
    rmse_hold: float
    k: int
    n_eff: float
    at_bound: tuple = ()

    @property
    def names(self) -> tuple:
        return tuple(n for n, _ in self.model.effects)


def rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(r)))) if r.size else math.nan


HUBER = 3.0   # robust_rms: residuals beyond this many robust standard deviations count linearly


def robust_rms(r: np.ndarray) -> float:
    """RMS of r with Huber's loss: samples within HUBER robust standard deviations (1.4826 MAD) count
    squared, those beyond linearly. The fit part's score for the information criterion and for picking
    among starts: a real recording carries events no model explains (the MRDLab rig switching its
    reaction torque on 0.5 s into each run holds a large share of the fit part's squared residual), and a
    plain RMS lets them decide between models that differ everywhere else. Close to `rms` for residuals
    without such events (Gaussian noise)."""
    if not r.size:
        return math.nan
    c = HUBER * 1.4826 * float(np.median(np.abs(r - np.median(r))))
    a = np.abs(r)
    if c <= 0:
        return rms(r)
    rho = np.where(a <= c, a * a, 2.0 * c * a - c * c)
    return float(np.sqrt(np.mean(rho)))


def effective_n(r: np.ndarray) -> float:
    """Effective number of independent samples of residual r: n (1 - rho) / (1 + rho), rho = lag-1 corr."""
    r = r - r.mean()
    den = float(np.dot(r, r))
    rho = float(np.dot(r[1:], r[:-1]) / den) if den > 0 else 0.0
    rho = min(max(rho, 0.0), 0.999)
    return max(r.size * (1 - rho) / (1 + rho), 10.0)


def delta_bic(new: "Fit", old: "Fit") -> float:
    """BIC(new) - BIC(old), n ln(RSS/n) + k ln n on the new fit's effective sample count (< 0: new pays)."""
    n = new.n_eff
    return n * math.log(max(new.rmse_fit, 1e-300) ** 2 / max(old.rmse_fit, 1e-300) ** 2) + (new.k - old.k) * math.log(n)


def applicable(d: LinkData, baseline: bool = False) -> list[str]:
    """Catalogue effects that can be added on this link given its channels (baseline: also those never
    named as findings, which a baseline may still contain)."""
    have = {"t", "v", "x", "load", "force", "d", "d_dot"}
    if d.x is None:
        have -= {"x", "v"}
    if d.link.kind == "position" and d.load is None:
        have.discard("load")
    if d.link.kind != "contact":
        have -= {"d", "d_dot"}
    if d.temperature is not None:
        have.add("temperature")
    if d.theta is not None:
        have.add("theta")
    out = []
    for name, eff in sorted(REGISTRY.items()):
        if eff.link not in d.link.effect_kinds or (not eff.rules.finding and not baseline):
            continue
        if all(i in have for i in eff.inputs):
            out.append(name)
    return out


def _target_signals(d: LinkData, m: LinkModel, name: str):
    """Signals and target for the data-driven guess of effect `name` appended to model m's chain."""
    sig = effect_signals(d, m)
    eff = get_effect(name)
    if eff.link == "sensor":
        return sig.replace(force=predict(d, m)), d.y
    if d.link.kind == "position":
        z = predict(d, m)
        if d.link.through_spring:   # effects act on the tip travel, in the input's units
            g = m.gain if m.gain != 0 else 1.0
            return sig.replace(x=(z - m.offset) / g), (d.y - m.offset) / g
        return sig.replace(x=z), d.y
    if d.link.kind == "force":
        z = predict(d, m) - m.offset
        return sig.replace(load=z), d.y - m.offset
    if is_contact_law(name):
        return sig, d.y - m.offset
    return fast_replace(sig, force=predict(d, m) - m.offset), d.y - m.offset


def held_params(d: LinkData, name: str, p: dict, free_shape: tuple = ()) -> dict:
    """Parameters of effect `name` (current values p) that a fit of the chain holds: fixed_params, and the
    general form's parameters (ParamSpec.shape) while they are at their plain defaults, unless named
    "name.param" in free_shape (a chain whose effect has its general form keeps fitting it)."""
    out = fixed_params(d, name, general=True)
    for spec in get_effect(name).params:
        if spec.shape and f"{name}.{spec.name}" not in free_shape and p.get(spec.name, spec.default) == spec.default:
            out.setdefault(spec.name, spec.default)
    return out


def fit_chain(d: LinkData, start: LinkModel, names: tuple, fit_idx: slice, hold_idx: slice,
              starts: int = 1, seed: int = 0, freeze: bool = False, free_shape: tuple = ()) -> Fit:
    """Fit baseline gain/offset and the parameters of effects `names` (appended to start's chain);
    freeze: keep the parameters of start's effects but their states (ParamSpec.state; a quick screen of an
    addition); free_shape: general form parameters ("effect.param") fitted as well (see held_params).
    Memoised per link data (`_memo`): the same fit asked for twice (an exact drive's rate probe, then the same
    candidate in the search) is the same Fit."""
    key = _memo_key("fit", start, names, fit_idx, hold_idx, starts, seed, freeze, free_shape)
    return _memo(d, key, lambda: _fit_chain(d, start, names, fit_idx, hold_idx, starts, seed, freeze, free_shape))


def _model_key(m: LinkModel) -> tuple:
    return (m.link, m.gain, m.offset, m.direction, m.load_sign, m.base,
            tuple((n, tuple(p.items())) for n, p in m.effects))


def _memo_key(*parts) -> tuple | None:
    """A hashable key of fit arguments (models, slices, tuples, numbers), or None where one is not (an index
    array: not memoised)."""
    out = []
    for a in parts:
        if isinstance(a, LinkModel):
            a = _model_key(a)
        elif isinstance(a, slice):
            a = ("slice", a.start, a.stop, a.step)
        elif isinstance(a, np.ndarray):
            return None
        out.append(a)
    return tuple(out)


def _memo(d: LinkData, key, run):
    """run(), memoised in d.cache under key (None: not memoised); exceptions are not."""
    memo = d.cache.setdefault("fits", {})
    try:
        if key is not None and key in memo:
            return memo[key]
    except TypeError:   # an unhashable parameter value
        return run()
    out = run()
    if key is not None:
        memo[key] = out
    return out


def _fit_chain(d: LinkData, start: LinkModel, names: tuple, fit_idx: slice, hold_idx: slice, starts: int,
               seed: int, freeze: bool, free_shape: tuple) -> Fit:
    effects = list(start.effects)
    known = {n for n, _ in effects}
    for name in names:
        if name not in known:
            sig, target = _target_signals(d, LinkModel(start.link, start.gain, start.offset, start.direction,
                                                       start.load_sign, tuple(effects), start.base), name)
            p0 = get_effect(name).initial_guess(sig, target)
            p0.update(fixed_params(d, name, direction=start.direction))
            effects.append((name, p0))
    # free parameter layout: gain, offset, then each effect's free params in the unit space of its specs
    layout, k = [], 2
    for i, (name, p) in enumerate(effects):
        held = held_params(d, name, p, free_shape)
        for spec in get_effect(name).params:
            if spec.name not in held:
                k += 1
                if not (freeze and i < len(start.effects)) or spec.state:   # a state is the record's own
                    layout.append((i, spec))
    ysc = max(float(np.std(d.y[fit_idx])), 1e-12)
    g0 = start.gain if start.gain != 0 else 1.0
    dt = float(np.median(np.diff(d.t[:100])))
    samples = fit_samples(d, fit_idx, dt)
    dfit = d.window(samples)
    # each sample weighs the stretch of record it stands for (a uniform record's least squares)
    wts = None if isinstance(samples, slice) else np.sqrt(sample_weights(samples))
    contact_law = d.link.kind == "contact" and any(is_contact_law(n) for n, _ in effects)

    def unpack(w):
        gain = g0 * (1.0 + w[0])
        offset = start.offset + w[1] * ysc
        chain = [(n, dict(p)) for n, p in effects]
        for (i, spec), wi in zip(layout, w[2:]):
            chain[i][1][spec.name] = spec.from_unit(0.5 * (1.0 + math.sin(wi)))
        return LinkModel(start.link, gain, offset, start.direction, start.load_sign, tuple(chain), start.base)

    def resid(w, data):
        r = (predict(data, unpack(w)) - data.y) / ysc
        if wts is not None:
            r = r * wts
        return r if np.isfinite(r).all() else np.nan_to_num(r, nan=1e3, posinf=1e3, neginf=-1e3)

    # bounded unit-space parameters u in [0, 1] enter as u = (1 + sin w) / 2 (unbounded w: MINPACK's
    # Levenberg-Marquardt, no BLAS threads); a parameter ending on a bound shows as u in {0, 1}
    u0 = np.array([spec.to_unit(spec.clip(effects[i][1][spec.name])) for i, spec in layout])
    w0 = np.concatenate([[0.0, 0.0], np.arcsin(np.clip(2.0 * u0 - 1.0, -0.999, 0.999))])
    if contact_law:  # the contact effect carries the stiffness: the baseline gain is not used
        g0 = 0.0
    rng = np.random.default_rng(seed)
    best = None
    if len(layout) >= 3:  # three or more shape parameters (Stribeck): local minima, try more starts
        starts = max(starts, 3)
    starts = max([starts] + [get_effect(n).rules.starts for n in names])
    for s in range(max(starts, 1)):
        w = w0.copy()
        if s > 0:
            w[2:] = w[2:] + rng.normal(0.0, 0.5, len(layout))
        res = least_squares(resid, w, args=(dfit,), method="lm", x_scale=1.0, diff_step=1e-4,
                            max_nfev=40 + 20 * len(w))
        if best is None or res.cost < best.cost:
            best = res
    model = unpack(best.x)
    r_all = predict(d, model) - d.y
    r_fit = r_all[fit_idx]
    n_eff = effective_n(best.fun)
    # standard errors: cov = s^2 (J^T J)^-1 inflated by n / n_eff for correlated residuals
    m = best.fun.size
    cov = parameter_covariance(best.jac, residual_variance(best.fun, best.x.size) * (m / n_eff))
    stderr = {n: {} for n, _ in model.effects}
    for j, (i, spec) in enumerate(layout):
        name, p = model.effects[i]
        dudw = 0.5 * abs(math.cos(best.x[j + 2]))
        stderr[name][spec.name] = float(abs(spec.dvalue_du(p[spec.name])) * dudw
                                        * math.sqrt(max(cov[j + 2, j + 2], 0)))
    stderr["baseline"] = {"gain": float(abs(g0) * math.sqrt(max(cov[0, 0], 0))),
                          "offset": float(ysc * math.sqrt(max(cov[1, 1], 0)))}
    rf = robust_rms(r_fit)
    # a baseline effect may end on a bound (mu = 0: this sheath has no capstan friction); an added
    # effect that does has the wrong form for the data
    pinned = tuple(f"{model.effects[i][0]}.{spec.name}" for (i, spec), wi in zip(layout, best.x[2:])
                   if i >= model.base and not spec.state and min(1 + math.sin(wi), 1 - math.sin(wi)) < 2e-3)
    return Fit(model, stderr, rf, rms(r_all[hold_idx]), k, n_eff, pinned)


def baseline_fit(d: LinkData, fit_idx: slice, hold_idx: slice) -> Fit:
    """The baseline alone, as a Fit."""
    m = fit_baseline(d, fit_idx)
    r = predict(d, m) - d.y
    n_eff = effective_n(r[fit_idx])
    rf = robust_rms(r[fit_idx])
    return Fit(m, {"baseline": {"gain": 0.0, "offset": 0.0}}, rf, rms(r[hold_idx]), 2, n_eff)


def wrong_form(name: str, params: dict, d: LinkData) -> bool:
    """True when fitted parameters contradict the effect's defining signature (Rules.wrong_form; then it
    is not named)."""
    rule = get_effect(name).rules.wrong_form
    return rule is not None and bool(rule(params, record(d)))


def _pick(cands: list[Fit], d: LinkData) -> Fit | None:
    """Best held-out RMSE, preferring fewer parameters among candidates within PARSIMONY of it; fits
    with a parameter pinned on its bound (the effect's form does not fit the data) never win."""
    cands = [c for c in cands if not c.at_bound and not any(wrong_form(n, p, d) for n, p in c.model.effects)]
    return _parsimonious(cands) if cands else None


def _pick_paying(cands: list[Fit], current: Fit, floor: float, d: LinkData) -> Fit | None:
    """`_pick` among the candidates that pay on `current` (`_pays` with the noise `floor`), else among all:
    parsimony among equals, and a simpler candidate within PARSIMONY that does not pay is no equal of one
    that does (a viscous friction 6 % behind a Dahl friction that reaches the noise floor)."""
    return _pick([f for f in cands if _pays(f, current, floor)], d) or _pick(cands, d)


def _parsimonious(items: list, fit=lambda item: item):
    """The item whose Fit (fit(item)) has the fewest parameters among those within PARSIMONY of the best
    held-out RMSE (ties: the lower RMSE)."""
    best = min(fit(c).rmse_hold for c in items)
    close = [c for c in items if fit(c).rmse_hold <= best * (1 + PARSIMONY)]
    return min(close, key=lambda c: (fit(c).k, fit(c).rmse_hold))


@dataclass(frozen=True)
class LinkResult:
    """Outcome for one link: baseline Fit, accepted steps [(Fit before, Fit after)], every first-round
    candidate Fit by name (the ranking evidence), and the final Fit."""

    data: LinkData
    baseline: Fit
    steps: tuple
    ranking: dict
    final: Fit
    delay: tuple = ()      # (tau [s], held-out RMSE) of the delayed ideal link, when it rivals the effects


MAX_DELAY_S = 0.25


def delay_fit(d: LinkData, fit_idx: slice, hold_idx: slice, base: LinkModel | None = None) -> tuple[float, float]:
    """(tau [s], held-out RMSE) of the baseline link with a pure delay of its output, y(t) = sim(u)(t - tau)
    refitted affinely, |tau| <= MAX_DELAY_S: the uncatalogued alternative a lag-like effect must beat (a
    sensor or transport delay is not backlash or friction)."""
    dt = float(np.median(np.diff(d.t[:100])))
    if base is None or not base.effects:
        sim = np.maximum(d.u, 0.0) if d.link.kind == "contact" else d.u
    else:
        sim = predict(d, base)
    stride = max(1, (fit_idx.stop - (fit_idx.start or 0)) // FIT_SAMPLES)
    fi = np.arange(fit_idx.start or 0, fit_idx.stop, stride)
    best = (0.0, math.inf, 0.0, 0.0)
    for tau in np.linspace(-MAX_DELAY_S, MAX_DELAY_S, 2 * int(MAX_DELAY_S / max(dt, 2e-3)) + 1):
        us = np.interp(d.t - tau, d.t, sim)
        A = np.column_stack([us[fi], np.ones(fi.size)])
        (g, c), *_ = np.linalg.lstsq(A, d.y[fi], rcond=None)
        r = rms(d.y[fi] - A @ np.array([g, c]))
        if r < best[1]:
            best = (float(tau), r, float(g), float(c))
    tau, _, g, c = best
    us = np.interp(d.t - tau, d.t, sim)
    return tau, rms((d.y - (g * us + c))[hold_idx])


TIE = 1e-4   # simulation_baseline: fits whose fit-part scores differ by less than this fraction tie (the
             # fit part cannot tell them apart: their optimisers stopped at its noise)


def _at_limits(m: LinkModel) -> int:
    """The number of m's effect parameters at an end of their range (within 1 % of it in unit space: a log
    stiffness over 12 decades within its top 0.12 decade); a shape parameter that must pay on its own, at its
    plain default, is not counted (held there, it is no limit the fit reached: `_baseline_shape` frees it)."""
    return sum(1 for n, p in m.effects for s in get_effect(n).params
               if s.name in p and not (s.shape and s.alone and p[s.name] == s.default)
               and min(s.to_unit(s.clip(p[s.name])), 1.0 - s.to_unit(s.clip(p[s.name]))) < 1e-2)


def simulation_baseline(d: LinkData, fit_idx: slice, hold_idx: slice, names: tuple = (), seed: int = 0) -> Fit:
    """The baseline: the ideal link with the baseline effects `names` that this link's channels allow
    (e.g. the sheath's capstan friction over the recorded bend), fitted jointly with gain and offset.
    Memoised per link data (an exact drive's rate probe fits it before the search does)."""
    key = _memo_key("baseline", fit_idx, hold_idx, tuple(names), seed)
    return _memo(d, key, lambda: _simulation_baseline(d, fit_idx, hold_idx, names, seed))


def _simulation_baseline(d: LinkData, fit_idx: slice, hold_idx: slice, names: tuple, seed: int) -> Fit:
    base = baseline_fit(d, fit_idx, hold_idx)
    names = tuple(n for n in names if n in applicable(d, baseline=True))
    if not names:
        return base
    start = base.model.with_effects(())
    # a load read from a spring's travel has no known zero: the sheath grips the spring's tension, the load
    # plus a pretension, so the baseline effects' general form (the capstan's preload) is the baseline's own
    general = d.link.spring_load
    free = tuple(f"{n}.{s.name}" for n in names for s in get_effect(n).params
                 if s.shape and not s.alone) if general else ()
    fits = []
    try:
        fits.append(fit_chain(d, start, names, fit_idx, hold_idx, starts=2, seed=seed, free_shape=free))
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):
        pass
    idx = np.arange(fit_idx.start or 0, fit_idx.stop)
    for name in names:   # an effect's own starts in a baseline (Rules.baseline_starts: the capstan's lines)
        rule = get_effect(name).rules.baseline_starts
        if rule is None:
            continue
        others = tuple(n for n in names if n != name)
        for direction, g_s, c_s, p0 in rule(record(d), idx, start.gain, start.offset, start.direction):
            try:
                seeded = LinkModel(start.link, g_s, c_s, direction, start.load_sign,
                                   ((name, {**p0, **fixed_params(d, name, general=general)}),))
                fits.append(fit_chain(d, seeded, others, fit_idx, hold_idx, seed=seed, free_shape=free))
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                pass
    if not fits:
        return base
    low = min(f.rmse_fit for f in fits)
    # among fits the fit part cannot tell apart, the one with more parameters at their limits (the limit
    # law: a stiff stick whose transitions the fit part never sees cross late is the instant switch)
    fit = max((f for f in fits if f.rmse_fit <= low * (1.0 + TIE)), key=lambda f: _at_limits(f.model))
    fit = _baseline_shape(d, fit, free, fit_idx, hold_idx, seed)
    m = fit.model
    return Fit(LinkModel(m.link, m.gain, m.offset, m.direction, m.load_sign, m.effects, len(m.effects)),
               fit.stderr, fit.rmse_fit, fit.rmse_hold, fit.k, fit.n_eff, fit.at_bound)


def baseline_shapes(names) -> tuple:
    """("effect.param") the baseline effects' shape parameters that must pay on their own (ParamSpec.alone and
    shape: the capstan's transition spread): the baseline's own choice (`_baseline_shape`), never a finding."""
    return tuple(f"{n}.{s.name}" for n in names for s in get_effect(n).params if s.shape and s.alone)


def _baseline_shape(d: LinkData, fit: Fit, free: tuple, fit_idx: slice, hold_idx: slice, seed: int) -> Fit:
    """The baseline `fit` (its shape parameters `baseline_shapes` at their plain defaults, `free` the general
    form's fitted beside them), or the baseline refitted with those parameters free, from the middle of
    their range, where that pays on its own (`_alone_pays`' rule: held-out RMSE lower by PARSIMONY and a
    better information criterion). Not tried where moving them changes nothing at the fitted values (an
    instant switch, a linear stick: the transition's curve does not show)."""
    shapes = tuple(k for k in baseline_shapes(fit.names)
                   if k.split(".", 1)[1] not in d.known.get(k.split(".", 1)[0], {}))   # the user's given value
    if not shapes:
        return fit
    chain = [(n, dict(p)) for n, p in fit.model.effects]
    for key in shapes:
        name, par = key.split(".", 1)
        spec = get_effect(name).spec(par)
        next(p for n, p in chain if n == name)[par] = spec.from_unit(0.5)
    start = fit.model.with_effects(tuple(chain))
    if np.allclose(predict(d, start), predict(d, fit.model), rtol=0.0,
                   atol=1e-9 * max(float(np.std(d.y)), 1e-12)):
        return fit
    try:
        g = fit_chain(d, start, (), fit_idx, hold_idx, seed=seed, free_shape=free + shapes)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):
        return fit
    return g if g.rmse_hold * (1 + PARSIMONY) <= fit.rmse_hold and delta_bic(g, fit) < 0 else fit


def identify_link(d: LinkData, fit_idx: slice, hold_idx: slice, progress=None, seed: int = 0,
                  baseline: tuple = ()) -> LinkResult:
    """Greedy identification on one link beyond its baseline (`simulation_baseline` with the effects
    `baseline`); see the module docstring."""
    base = simulation_baseline(d, fit_idx, hold_idx, baseline, seed)
    ranking = {}
    pool = [n for n in applicable(d) if n not in base.names]
    # an effect whose law a baseline effect already is on this data is no candidate (Rules.not_beside)
    pool = [n for n in pool if not set(get_effect(n).rules.not_beside) & set(base.names)]
    steps, current, delay = _grow(d, base, (), pool, 0, fit_idx, hold_idx, seed, progress, ranking)
    if not delay and any(s.shape for n in base.names for s in get_effect(n).params):
        steps, current = _general_baseline(d, base, tuple(steps), current, fit_idx, hold_idx, seed)
    return LinkResult(d, base, steps, ranking, current, delay)


def _general_baseline(d: LinkData, base: Fit, steps: tuple, current: Fit, fit_idx: slice, hold_idx: slice,
                      seed: int) -> tuple:
    """(steps, final Fit) with the baseline's own effects in their general form where that pays (the
    sheath gripping a pretension beside the load), tried once the catalogue's additions are exhausted, in
    place of them: reported as a finding it must pay as one (ACCEPT and the information criterion), and
    where the link took additions it must beat them by more than PARSIMONY (a pretension beside a capstan
    with sharp transitions is the same law as a Coulomb friction beside it, and then the catalogue's name
    stands). It is not added on top of them: beside another friction it absorbs what the recording does
    not carry (the session's Coulomb cable without its bend column, whose wrap varies with the pose: a
    pretension paid there)."""
    alone = general_form(d, base, list(base.names), fit_idx, hold_idx, seed, hold=baseline_shapes(base.names))
    if alone is base or not generalised(base, alone) or not _pays(alone, base):
        return steps, current
    if current is base or (alone.rmse_hold * (1 + PARSIMONY) < current.rmse_hold
                           and delta_bic(alone, current) < 0):
        return ((base, alone),), alone
    return steps, current


def generalised(before: Fit, after: Fit) -> list[str]:
    """Effects of `after` that `before` has in their plain form and `after` in their general form (a
    general-form parameter off its plain value; `general_form` has checked that the departure pays)."""
    plain = {n for n, p in before.model.effects
             if all(p.get(s.name, s.default) == s.default for s in get_effect(n).params if s.shape)}
    out = []
    for n, p in after.model.effects:
        if n in plain and any(abs(s.to_unit(p[s.name]) - s.to_unit(s.default)) > 1e-6
                              for s in get_effect(n).params if s.shape and not s.state):
            out.append(n)
    return out


def added(before: Fit, after: Fit) -> list[str]:
    """What a step adds: the effects new in `after`, or else those it turns to their general form."""
    return [n for n in after.names if n not in before.names] or generalised(before, after)


def _grow(d: LinkData, current: Fit, steps: tuple, pool: list, first_round: int, fit_idx: slice,
          hold_idx: slice, seed: int, progress, ranking: dict) -> tuple:
    """The greedy rounds from `first_round` on, from the chain `current` reached by `steps`: (steps,
    final Fit, delay). Where an added effect's general form pays (`general_form`), the plain form and the
    general one each continue (the general form competes with the effects the plain one could still take:
    a play's gradual take-up or a pulley's elongation), and the final chain with the better held-out RMSE is
    kept (within PARSIMONY, the one with fewer parameters)."""
    steps = list(steps)
    delay = ()
    for round_ in range(first_round, MAX_EFFECTS):
        # a held-out RMSE within ACCEPT of the residual's white noise: no addition can pay (none fits below
        # the noise), and fitting them all only gives chance a turn
        floor = max(noise_level(d.y - predict(d, current.model)), ROUND_OFF_SHARE * float(np.ptp(d.y)))
        if current.rmse_hold < ACCEPT * floor:
            break
        cands, by_name = [], {}
        for name in pool:
            if name in current.names:
                continue
            try:
                # a position-only force moves the gain, and the gain multiplies the load's own hysteresis
                # loop, which a friction already in the chain had taken its share of: the chain refits too
                f = fit_chain(d, current.model, (name,), fit_idx, hold_idx, seed=seed,
                              freeze=round_ > 0 and not position_only(name))
                restarts = get_effect(name).rules.gain_restarts
                if restarts and d.link.kind == get_effect(name).link and not current.model.effects:
                    f = min([f] + _gain_restarts(d, current.model, name, restarts, fit_idx, hold_idx, seed),
                            key=lambda g: g.rmse_fit)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
            if round_ == 0:
                ranking[name] = f
            cands.append(f)
            by_name[name] = f
            if position_only(name) or get_effect(name).rules.general_candidate:
                cands.extend(_curved(d, f, name, fit_idx, hold_idx, seed))
            if progress is not None:
                progress(1)
        for name, f in list(by_name.items()):   # an effect also fitted from the simpler one it extends
            g = _nested(d, f, name, by_name, fit_idx, hold_idx, seed)
            if g is not f:
                cands[next(i for i, c in enumerate(cands) if c is f)] = g
                if round_ == 0:
                    ranking[name] = g
        cands = [f for f in cands if not load_alike(d, current, f, hold_idx)]
        if not cands:
            break
        pick = _pick_paying(cands, current, floor, d)
        if round_ > 0:
            # the screen holds the chain's effects as they were fitted, and an effect fitted first absorbs
            # what it can of the next (a Coulomb friction takes the steady part of a Dahl's, a thermal drift
            # fitted first leaves a Coulomb that a Stribeck mimics): the best few screened additions are
            # refitted jointly with the chain and the pick is made among those. Where no screened addition
            # paid, the joint one must pay the threshold twice over (the joint refit frees the whole chain)
            joint = []
            for f in sorted(cands, key=lambda g: g.rmse_hold)[:PAIR_TOP]:
                if position_only(_new(current, f)[-1]):   # fitted with the chain free already
                    joint.append(f)
                    continue
                try:
                    joint.append(fit_chain(d, f.model, (), fit_idx, hold_idx, seed=seed))
                except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                    pass
            refit = _pick(joint, d)
            if _pays(pick, current, floor):
                if _pays(refit, current, floor):
                    pick = refit
            elif refit is not None and refit.rmse_hold * ACCEPT ** 2 <= current.rmse_hold:
                pick = refit
        if round_ == 0 and d.link.kind != "contact":
            tau, r_delay = delay_fit(d, fit_idx, hold_idx, current.model)   # round 0: the baseline
            if abs(tau) > 0 and r_delay * ACCEPT <= current.rmse_hold and (
                    pick is None or r_delay * (1 + PARSIMONY) < pick.rmse_hold):
                delay = (tau, r_delay)   # a plain delay explains it better: name nothing
                break
        pays = _pays(pick, current, floor)
        if pays and foreign(d, current, pick, fit_idx, hold_idx):
            break
        if not pays and round_ == 0 and len(cands) >= 2 and current.rmse_hold >= ACCEPT ** 2 * floor:
            pair = _pair(d, current, cands, fit_idx, hold_idx, seed)
            if pair:
                steps.extend(pair)
                current = pair[-1][1]
                continue
        if not pays:
            break
        general = general_form(d, pick, _new(current, pick), fit_idx, hold_idx, seed)
        if general is not pick:
            ends = [_grow(d, f, tuple(steps) + ((current, f),), pool, round_ + 1, fit_idx, hold_idx, seed,
                          progress, ranking) for f in (general, pick)]
            return _parsimonious(ends, fit=lambda end: end[1])
        steps.append((current, pick))
        current = pick
    return tuple(steps), current, delay


def _nested(d: LinkData, f: Fit, name: str, by_name: dict, fit_idx: slice, hold_idx: slice, seed: int) -> Fit:
    """The candidate Fit `f` of effect `name`, or a better one (lower fit-part score) refitted from the fit
    of the simpler effect it extends (Rules.extends, among `by_name`: {effect: its candidate Fit this
    round}): that chain with the simpler effect replaced by this one, its shared parameters at the simpler
    one's values and the rest at each of Rules.nested_starts. Its extra parameters must still pay on
    held-out data: among candidates within PARSIMONY the simpler one wins (`_pick`)."""
    rule = get_effect(name).rules
    simple = by_name.get(rule.extends)
    if simple is None or rule.nested_starts is None:
        return f
    base = simple.model.without((rule.extends,))
    sig, _ = _target_signals(d, base, name)
    fitted = dict(simple.model.effects)[rule.extends]
    eff = get_effect(name)
    best = f
    for p0 in rule.nested_starts(fitted, sig):
        p = {**eff.defaults(), **{k: v for k, v in fitted.items() if k in eff.param_names}, **p0}
        p = {k: eff.spec(k).clip(v) for k, v in p.items()}
        p.update(fixed_params(d, name, direction=base.direction))
        seeded = simple.model.with_effects([(name, p) if n == rule.extends else (n, q)
                                            for n, q in simple.model.effects])
        try:
            g = fit_chain(d, seeded, (), fit_idx, hold_idx, seed=seed)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            continue
        if g.rmse_fit < best.rmse_fit:
            best = g
    return best


def _curved(d: LinkData, plain: Fit, name: str, fit_idx: slice, hold_idx: slice, seed: int) -> list:
    """[the position-only effect `name` of the Fit `plain` in its general form (ParamSpec.shape freed,
    the chain refitted with it)] as a candidate of its own where it beats the plain form as every general
    form must (held-out RMSE lower by PARSIMONY, a better information criterion), else []. Wherever the
    load follows the drive position, a position-only force's linear part is the baseline gain's to take
    and its curvature is what tells it apart, so the general form cannot wait for the plain one to pay.
    The same for an effect whose rules say so (Rules.general_candidate: a stretch under a load read at the
    motor, beyond the sheath's friction)."""
    eff = get_effect(name)
    shape = tuple(f"{name}.{s.name}" for s in eff.params if s.shape)
    starts = [plain.model]
    if eff.rules.general_candidate:   # also from the middle of the range of a shape parameter whose plain
        mid = {s.name: s.from_unit(0.5) for s in eff.params   # value is a bound (a gradient-free start there)
               if s.shape and s.to_unit(s.default) in (0.0, 1.0)}
        if mid:
            starts.append(plain.model.with_effects([(n, {**p, **mid} if n == name else p)
                                                    for n, p in plain.model.effects]))
    fits = []
    for start in starts:
        try:
            fits.append(fit_chain(d, start, (), fit_idx, hold_idx, seed=seed, free_shape=shape))
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            pass
    if not fits:
        return []
    f = min(fits, key=lambda g: g.rmse_fit)
    better = f.rmse_hold * (1 + PARSIMONY) <= plain.rmse_hold and delta_bic(f, plain) < 0
    # and the curvature must be what it gains by, not a better start of the plain form's parameters: the
    # same fit with the general form's parameters at their plain defaults is worse by PARSIMONY
    flat = _evaluate(d, with_plain(f.model, (name,)), fit_idx, hold_idx, plain.k)
    needed = flat.rmse_hold >= f.rmse_hold * (1 + PARSIMONY)
    return [f] if better and needed and not f.at_bound else []


def _pays(pick: Fit | None, current: Fit, floor: float = 0.0) -> bool:
    """An addition pays: a better information criterion, and a held-out RMSE lower by ACCEPT, or (with the
    residual's white noise `floor`, locate.noise_level) lower by NEAR_ACCEPT and within NEAR_FLOOR of the
    floor: where the baseline has already absorbed most of an effect (a capstan's mu takes a Dahl friction's
    steady part) what is left above the noise is small, and an addition that takes the chain from above
    ACCEPT of the floor (the search's own gate) down to it explains what there was to explain."""
    if pick is None or delta_bic(pick, current) >= 0:
        return False
    if pick.rmse_hold * ACCEPT <= current.rmse_hold:
        return True
    return floor > 0 and pick.rmse_hold * NEAR_ACCEPT <= current.rmse_hold and pick.rmse_hold <= NEAR_FLOOR * floor


def general_form(d: LinkData, pick: Fit, added: list, fit_idx: slice, hold_idx: slice, seed: int,
                 hold: tuple = ()) -> Fit:
    """`pick` with the general form of the effects it adds (ParamSpec.shape: backlash's elastic part, wide
    play, growth with position and start) when that form pays: held-out RMSE lower by more than PARSIMONY
    and a better information criterion. A shape parameter that ends on its plain bound is held there and
    the rest refitted once. Else `pick` as it is. hold: shape parameters ("effect.param") not freed here (the
    baseline's own choice, `baseline_shapes`)."""
    # a position-only effect's general form was a candidate of its own (_curved), under the same rule, and so
    # was one whose rules say so (Rules.general_candidate)
    free = tuple(f"{n}.{s.name}" for n in added if not (position_only(n) or get_effect(n).rules.general_candidate)
                 for s in get_effect(n).params if s.shape and f"{n}.{s.name}" not in hold)
    if not free:
        return pick
    for _ in range(2):
        try:
            f = fit_chain(d, pick.model, (), fit_idx, hold_idx, seed=seed, free_shape=free)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            return pick
        if not f.at_bound:
            break
        free = tuple(n for n in free if n not in f.at_bound)
        if not free:
            return pick
    if f.at_bound or f.rmse_hold * (1 + PARSIMONY) > pick.rmse_hold or delta_bic(f, pick) >= 0:
        return pick
    return _alone_pays(d, f, pick, free, fit_idx, hold_idx, seed)


def _alone_pays(d: LinkData, f: Fit, pick: Fit, free: tuple, fit_idx: slice, hold_idx: slice, seed: int) -> Fit:
    """The general form `f` (shape parameters `free` fitted from `pick`), or, where a freed parameter that
    must pay on its own (ParamSpec.alone) does not (the form refitted with it at its default is within
    PARSIMONY of `f` on held-out data, and pays over `pick` as a general form must), that refit; a parameter
    dropped so stays held at its default in the next one's refit."""
    dropped = ()
    for key in free:
        name, par = key.split(".", 1)
        spec = get_effect(name).spec(par)
        if not spec.alone or dict(f.model.effects)[name][par] == spec.default:
            continue
        rest = tuple(k for k in free if k != key and k not in dropped)
        try:
            g = fit_chain(d, pick.model, (), fit_idx, hold_idx, seed=seed, free_shape=rest) if rest else pick
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            continue
        pays = g.rmse_hold * (1 + PARSIMONY) <= pick.rmse_hold and delta_bic(g, pick) < 0
        if pays and g.rmse_hold <= f.rmse_hold * (1 + PARSIMONY) and not g.at_bound:
            f, dropped = g, dropped + (key,)
    return f


def _gain_restarts(d: LinkData, start: LinkModel, name: str, factors: tuple, fit_idx: slice, hold_idx: slice,
                   seed: int) -> list:
    """Effect `name` refitted from the baseline gain times each of `factors` (Rules.gain_restarts: a wide
    play flattens the affine least-squares gain, so its fit can end at a too-small gain)."""
    out = []
    for factor in factors:
        try:
            out.append(fit_chain(d, LinkModel(start.link, start.gain * factor, start.offset, start.direction,
                                              start.load_sign, (), start.base), (name,),
                                 fit_idx, hold_idx, seed=seed))
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            pass
    return out


#: conditions no catalogue effect has as its signature: an effect whose own contribution is best located there
#: is absorbing physics outside the catalogue (a pulley's eccentricity, cogging) and is not named
FOREIGN = ("periodic in position",)


def foreign(d: LinkData, current: Fit, pick: Fit, fit_idx: slice, hold_idx: slice) -> bool:
    """True when the effect `pick` adds to `current` acts where no catalogue effect does (FOREIGN, on the
    held-out part and on the fit part alike), or is a
    position-only effect that a sinusoid in position beats (`periodic_beats`); never when all it adds is
    periodic in position itself (Rules.periodic: a transmission error is that map, named)."""
    new = _new(current, pick)
    if new and all(get_effect(n).rules.periodic for n in new):
        return False
    if periodic_beats(d, current, pick, fit_idx, hold_idx):
        return True
    # a location the record's two parts agree on: the best of many harmonics explains some of any
    # switching contribution by chance on one part (a tip sensor's hysteresis on strokes), a periodic one on both
    y0, change = predict(d, current.model), _change(d, pick, new)
    return all(locate(d, d.y - y0, d.y, index=part, change=change).condition in FOREIGN
               for part in (hold_idx, fit_idx))


def _new(current: Fit, pick: Fit) -> list[str]:
    """Names of the effects `pick` adds to `current`."""
    return [n for n in pick.names if n not in current.names]


def _change(d: LinkData, pick: Fit, new: list[str]) -> np.ndarray:
    """(n,) the contribution of effects `new` to `pick`'s prediction: with them minus without them."""
    return predict(d, pick.model) - predict(d, pick.model.without(new))


def periodic_beats(d: LinkData, current: Fit, pick: Fit, fit_idx: slice, hold_idx: slice) -> bool:
    """True when `pick` adds a position-only effect (`position_only`) and a sinusoid in position fitted on top
    of `current` (`periodic_rmse`) does as well on held-out data (within PARSIMONY, or better): the spring's
    contribution is by construction a function of position, so its location cannot tell it from a
    pulley's eccentricity; its shape can, where it fits clearly better (a spring's curvature standing in
    for a late load sensor fits no better than the sinusoid)."""
    return (any(position_only(n) and not get_effect(n).rules.periodic for n in _new(current, pick))
            and periodic_rmse(d, current.model, fit_idx, hold_idx) < pick.rmse_hold * (1 + PARSIMONY))


def periodic_rmse(d: LinkData, model: LinkModel, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out RMSE of `model` plus the sinusoid in the drive position (the harmonic over the travel that
    projects most of the fit part's residual, locate.periodic_features; amplitude, phase and a constant by
    least squares on the fit part): the uncatalogued alternative a position-only effect must beat."""
    r = d.y - predict(d, model)
    A = np.column_stack([np.ones(d.n), periodic_features(travel_phase(d.x), r, fit_idx)])
    coef, *_ = np.linalg.lstsq(A[fit_idx], r[fit_idx], rcond=None)
    return rms((r - A @ coef)[hold_idx])


def position_only(name: str) -> bool:
    """An effect of the drive position alone (Rules.position_only): told apart from the load only where the
    load is not itself a function of the position, and from a periodic force (an eccentric pulley) by its
    shape."""
    return get_effect(name).rules.position_only

LOAD_ALIKE_R2 = 0.95


def load_alike(d: LinkData, current: Fit, pick: Fit, hold_idx: slice) -> bool:
    """True (the candidate is dropped) when `pick` adds a position-only effect (`position_only`) whose own
    contribution the link's load explains (R^2 >= LOAD_ALIKE_R2 on the held-out part): a spring-loaded
    tip's force is its position times the spring rate, and a parallel spring there is a change of the
    baseline gain, or whatever else the gain and a position term can mimic together (a delayed load
    sensor), not a spring beside the transmission. In its general form the test is on the part no gain
    can take, the contribution of the general form's parameters (a spring's curvature): the linear part
    trades freely with the gain wherever the load follows the position, whatever its size."""
    new = _new(current, pick)
    if d.link.kind != "force" or not any(position_only(n) for n in new):
        return False
    plain = with_plain(pick.model, new)
    change = predict(d, pick.model) - predict(d, plain) if plain != pick.model else _change(d, pick, new)
    return r2(change[hold_idx], d.u[hold_idx, None]) >= LOAD_ALIKE_R2


def with_plain(model: LinkModel, names) -> LinkModel:
    """`model` with the effects `names` in their plain form (ParamSpec.shape parameters at their defaults)."""
    return model.with_effects([(n, {**p, **get_effect(n).plain_form()} if n in names else p)
                               for n, p in model.effects])


PAIR_TOP = 3   # when no single effect pays, pairs of the best few singles (held-out, fit) are fitted jointly


def _evaluate(d: LinkData, model: LinkModel, fit_idx: slice, hold_idx: slice, k: int) -> Fit:
    """A Fit of `model` as it is (no refit): RMSEs on fit and held-out samples."""
    r = predict(d, model) - d.y
    return Fit(model, {}, robust_rms(r[fit_idx]), rms(r[hold_idx]), k, effective_n(r[fit_idx]))


def _pair(d: LinkData, current: Fit, cands: list, fit_idx: slice, hold_idx: slice, seed: int) -> list:
    """Two effects whose signatures cancel in part (a tip sensor's hysteresis against the play it reads
    through a spring) can each fail alone and pay together: fit pairs of the PAIR_TOP best singles
    jointly; the best pair that pays, and whose every member the pair needs (>= ACCEPT lost without it),
    is returned as one step adding both."""
    # the best few on held-out data and the best few on the fit part: an effect whose held-out part is
    # spoiled by the other's (a viscous friction under a temperature drift that moves on after the fit
    # part) still fits the fit part best
    singles = sorted(cands, key=lambda f: f.rmse_hold)[:PAIR_TOP]
    singles += [f for f in sorted(cands, key=lambda f: f.rmse_fit)[:PAIR_TOP] if all(f is not g for g in singles)]
    names = [f.names[-1] for f in singles]
    best = None
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            # both orders: each starts the other effect from the residual the first leaves, and a joint fit
            # from one of them can settle in a local minimum (a play fitted under a hysteresis start)
            fits = []
            for pair in ((names[i], names[j]), (names[j], names[i])):
                try:
                    fits.append(fit_chain(d, current.model, pair, fit_idx, hold_idx, seed=seed))
                except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                    pass
            if not fits:
                continue
            f = min(fits, key=lambda g: g.rmse_fit)
            if f.at_bound or any(wrong_form(n, p, d) for n, p in f.model.effects):
                continue
            if periodic_beats(d, current, f, fit_idx, hold_idx):   # a spring in a pair faces the same guard
                continue
            if f.rmse_hold * ACCEPT ** 2 <= current.rmse_hold and delta_bic(f, current) < 0:
                if best is None or f.rmse_hold < best.rmse_hold:
                    best = f
    if best is None:
        return []
    a, b = best.names[-2], best.names[-1]
    k_one = current.k + len(get_effect(a).params)
    only_a = _evaluate(d, best.model.without((b,)), fit_idx, hold_idx, k_one)
    only_b = _evaluate(d, best.model.without((a,)), fit_idx, hold_idx, k_one)
    if min(only_a.rmse_hold, only_b.rmse_hold) < best.rmse_hold * ACCEPT:   # each one must be needed
        return []
    return [(current, best)]
