"""Diagnose a recording end to end: links -> baseline -> locate -> name effects -> report (JSON keys: docs/formats.md).

`diagnose(rec)` returns a `Diagnosis`: per link the identification result, and `as_dict()` gives the JSON
object {"recording", "channels", "baseline": {"params", "rmse"}, "findings": [...], "unexplained": [...]}
(plus "peer": the ARX comparison, "holdout"). RMSEs are measured on the held-out last part.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass

import numpy as np

from teleop.diagnosis.identify import (Fit, LinkResult, added, fit_chain, identify_link, rms, simulation_baseline,
                                      with_plain)
from teleop.core.physics.links import LinkData, is_exact, predict
from teleop.diagnosis.links import exact_turn_rate, find_links, link_data
from teleop.diagnosis.locate import locate, noise_level
from teleop.diagnosis.peer import arx_rmse
from teleop.diagnosis.sindy_peer import sindy_rmse
from teleop.io.recording_io import Recording
from teleop.core.errors import InputError
from teleop.core.physics import REGISTRY, get_effect

HOLDOUT = 0.4           # last 40 % of each recording scores the models
#: the project's simulation of a cable setup: the effects whose rules say so (Rules.baseline; the sheath's
#: capstan friction on the force link, over the recorded bend, or a fitted mu Theta where none is recorded);
#: the spring load is the position link's gain
PROJECT_BASELINE = tuple(n for n, e in REGISTRY.items() if e.rules.baseline)
#: the simplest law of the drive's rate (Rules.rate_probe), fitted to pick an exact drive's rate convention
RATE_PROBE = tuple(n for n, e in REGISTRY.items() if e.rules.rate_probe)[:1]
STRUCTURE = 2.0         # residual RMS above this many noise levels, with a condition explaining >= R2_MIN
R2_MIN = 0.3            # of it, is reported as unexplained


def baseline_effects(spec: str | None) -> tuple[str, ...]:
    """The catalogue effects a `--baseline` value names: 'default' (or None) -> the project's simulation
    (PROJECT_BASELINE), 'lossless' -> none (the ideal rigid, lossless link), else a comma list of
    catalogue names (each added to every link whose channels allow it)."""
    if spec is None or spec.strip() in ("", "default", "project"):
        return PROJECT_BASELINE
    if spec.strip() in ("lossless", "none", "ideal"):
        return ()
    names = tuple(n.strip() for n in spec.split(",") if n.strip())
    for n in names:
        try:
            get_effect(n)
        except InputError as exc:
            raise InputError(f"--baseline: {exc} (or 'default', 'lossless')") from None
    return names


def baseline_text(names: tuple) -> str:
    """One line saying what the baseline simulation is."""
    ideal = "ideal rigid lossless link: output = gain * input + offset (contact: gain * max(indentation, 0) + offset)"
    if not names:
        return ideal
    which = "the project's simulation" if names == PROJECT_BASELINE else "the user's simulation"
    return f"{which}: {ideal}, with {', '.join(names)} where the link's channels carry it"


def split(n: int, holdout: float) -> tuple[slice, slice]:
    """(fit, hold) slices: the first 1 - holdout of n samples fit, the rest score."""
    if not 0.05 <= holdout <= 0.8:
        raise InputError(f"holdout must be within [0.05, 0.8], got {holdout}")
    k = int(round(n * (1.0 - holdout)))
    return slice(0, k), slice(k, n)


def si_unit(spec_unit: str, pos_unit: str, force_unit: str) -> str:
    """A ParamSpec unit written for linear links ('N/m', 'm/s') in the link's own units (rad, N m)."""
    u = re.sub(r"\bN\b", "§F", spec_unit)
    u = re.sub(r"\bm\b", "§P", u)
    return u.replace("§F", force_unit).replace("§P", pos_unit)


def _link_units(rec: Recording, d: LinkData) -> tuple[str, str]:
    L = d.link
    if L.kind == "position":
        pos = rec.units[L.input if L.through_spring else L.output]
        force = rec.units.get(L.load, "N") if L.load else "N"
    elif L.kind == "force":
        pos = rec.units.get(L.drive, "m") if L.drive else "m"
        force = rec.units[L.output]
    else:
        pos, force = "m", "N"
    return pos, force


def _param_block(rec: Recording, d: LinkData, name: str, params: dict, stderr: dict) -> dict:
    pos, force = _link_units(rec, d)
    eff = get_effect(name)
    out = {}
    plain = not any(s.name in stderr for s in eff.params if s.shape)   # no general-form parameter fitted
    for spec in eff.params:
        if spec.shape and plain:   # the plain form: its general form's parameters say nothing
            continue
        se = stderr.get(spec.name)
        out[spec.name] = {"value": float(params[spec.name]),
                          "stderr": None if se is None else float(se),
                          "unit": si_unit(spec.unit, pos, force)}
        if se is None:
            out[spec.name]["fixed"] = True
        if spec.name in d.known.get(name, {}):
            out[spec.name]["known"] = True   # from the recording's metadata: the user's simulation has it
    return out


@dataclass(frozen=True)
class Diagnosis:
    """The diagnosis of one recording: rec, holdout, per-link results and the ARX peer RMSEs."""

    rec: Recording
    holdout: float
    links: tuple
    peer: dict
    baseline: tuple = PROJECT_BASELINE

    @property
    def hold(self) -> slice:
        return split(self.rec.n, self.holdout)[1]

    def findings(self) -> list[dict]:
        """Accepted effects over all links, most important (largest held-out improvement) first."""
        out = []
        for res in self.links:
            d = res.data
            for before, after, name in ((b, a, n) for b, a in res.steps for n in added(b, a)):
                y1 = predict(d, after.model)
                # the effect's own signature: the final model with and without it (same gain and offset),
                # or, where the step turns a baseline effect general, with it in its plain form
                refines = name in before.names   # a baseline effect turned general (before a pair's rebinding)
                if refines:
                    y1_without = predict(d, with_plain(after.model, (name,)))
                else:
                    y1_without = predict(d, after.model.without((name,)))
                if len(added(before, after)) > 1:
                    # a pair that pays only together: each one's share is what the pair loses without it
                    before = Fit(after.model, {}, math.nan, rms((d.y - y1_without)[self.hold]), after.k, after.n_eff)
                y0 = predict(d, before.model)
                loc = locate(d, d.y - y0, d.y, index=self.hold, change=y1 - y1_without)
                # the parameters as identified: the final model's (an effect added later is fitted jointly
                # with those before it, which then give up what they had absorbed of it)
                final = res.final
                params = dict(final.model.effects)[name]
                block = _param_block(self.rec, d, name, params, final.stderr.get(name, {}))
                for p in () if d.link.through_spring else get_effect(name).rules.input_units:
                    g = abs(final.model.gain)   # also in the input's (motor) units
                    w = block[p]
                    block[f"{p}_input"] = {"value": w["value"] / g,
                                           "stderr": None if w["stderr"] is None else w["stderr"] / g,
                                           "unit": self.rec.units[d.link.input], "derived": True}
                first = len(before.model.effects) == before.model.base
                alts = sorted(((n, f.rmse_hold) for n, f in res.ranking.items() if n != name),
                              key=lambda kv: kv[1])[:3] if first else []
                out.append({
                    "effect": name,
                    "channel": d.link.output,
                    "where": loc.as_dict(),
                    "params": block,
                    "rmse_before": before.rmse_hold,
                    "rmse_after": after.rmse_hold,
                    "improvement": before.rmse_hold / max(after.rmse_hold, 1e-300),
                    "link": d.link.kind,
                    "alternatives": [{"effect": n, "rmse_after": r} for n, r in alts],
                    **({"general_form_of_baseline": True} if refines else {}),
                })
        # importance: the channels by what their first finding explains (the improvement ratio, comparable
        # across units); within a channel the greedy order, each effect added where it explained most of what
        # was left (a Coulomb friction that takes 0.35 N to 0.055 N comes before the viscous friction that
        # takes 0.055 N to 0.004 N, though the latter's ratio is larger)
        # the general form of a baseline effect (a pretension the sheath grips) refines what the simulation
        # has: it comes after the effects the simulation lacks
        group = {id(f): (f.get("general_form_of_baseline", False), f["channel"]) for f in out}
        lead = {}
        for f in out:
            lead.setdefault(group[id(f)], f["improvement"])
        order = {id(f): k for k, f in enumerate(out)}
        out.sort(key=lambda f: (group[id(f)][0], -lead[group[id(f)]], f["channel"], order[id(f)]))
        return out

    def unexplained(self) -> list[dict]:
        """Structured residual left by the final model of each link, with its best correlate."""
        out = []
        for res in self.links:
            d = res.data
            r = d.y - predict(d, res.final.model)
            rh = r[self.hold]
            noise = max(noise_estimate(r), 1e-300)
            loc = locate(d, r, d.y, index=self.hold)
            best_r2 = loc.evidence[loc.condition]
            if res.delay:
                tau, r_delay = res.delay
                out.append({"channel": d.link.output, "link": d.link.kind,
                            "correlate": "delay between input and output", "delay_s": tau,
                            "r2": round(1.0 - (r_delay / max(rms(rh), 1e-300)) ** 2, 4), "rmse": rms(rh),
                            "rmse_delayed_link": r_delay, "noise_rmse": noise, "windows": loc.windows})
                continue
            scale = max(float(np.max(np.abs(d.y))), 1e-300)
            if rms(rh - rh.mean()) <= 1e-9 * scale:   # a constant channel (the robot did not move) holds nothing
                continue
            if rms(rh - rh.mean()) > STRUCTURE * noise and best_r2 >= R2_MIN:
                out.append({"channel": d.link.output, "link": d.link.kind, "correlate": loc.condition,
                            "r2": round(best_r2, 4), "rmse": rms(rh), "noise_rmse": noise,
                            "windows": loc.windows})
        return out

    def as_dict(self) -> dict:
        """The JSON object of docs/formats.md."""
        channels = {}
        for name, x in self.rec.channels.items():
            channels[name] = {"unit": self.rec.units[name]}
        base_params, base_rmse, base_effects = {}, {}, {}
        for res in self.links:
            d = res.data
            m = res.baseline.model
            pos, force = _link_units(self.rec, d)
            ch = d.link.output
            r = d.y - predict(d, m)
            loc = locate(d, r, d.y, index=self.hold)
            channels[ch].update({"link": d.link.kind, "input": d.link.input,
                                 **({"drive": d.link.drive, "drive_rate": _drive_rate(d)} if d.x is not None else {}),
                                 "rmse_baseline": res.baseline.rmse_hold,
                                 "rmse_model": res.final.rmse_hold,
                                 "residual": loc.as_dict()})
            in_unit = self.rec.units[d.link.input]
            base_params[ch] = {"gain": {"value": m.gain, "unit": f"{self.rec.units[ch]}/{in_unit}"},
                               "offset": {"value": m.offset, "unit": self.rec.units[ch]}}
            if d.link.kind == "force":
                base_params[ch]["direction"] = {"value": m.direction, "unit": "1"}
            for name, p in m.effects[: m.base]:
                base_params[ch][name] = _param_block(self.rec, d, name, p, res.baseline.stderr.get(name, {}))
            base_effects[ch] = list(m.baseline_names)
            base_rmse[ch] = res.baseline.rmse_hold
        return {
            "recording": self.rec.path,
            "channels": channels,
            "baseline": {"params": base_params, "rmse": base_rmse, "effects": base_effects,
                         "requested": list(self.baseline), "model": baseline_text(self.baseline)},
            "findings": self.findings(),
            "unexplained": self.unexplained(),
            "holdout": {"fraction": self.holdout, "t_start": float(self.rec.t[self.hold][0])},
            "peer": self.peer,
        }


def noise_estimate(r: np.ndarray) -> float:
    """The white noise [r's unit] on a channel, from its model's residual r (n,) (locate.noise_level: robust
    third differences): the level against which a residual left is structure (STRUCTURE) and a model's
    held-out RMSE is at the noise floor."""
    return noise_level(r)


def sensor_correction(res: LinkResult) -> np.ndarray | None:
    """(n,) what the sensor effects identified on a link add to its output channel's reading, or None; so
    do effects whose contribution may be the reading's own (Rules.reading: a late tip-force sensor)."""
    m = res.final.model

    def reading(n):
        return get_effect(n).link == "sensor" or get_effect(n).rules.reading
    if not any(reading(n) for n, _ in m.effects[m.base:]):
        return None
    plain = m.with_effects([(n, p) for n, p in m.effects if not reading(n)])
    return predict(res.data, m) - predict(res.data, plain)


def exact_rate(d: LinkData, fit_idx: slice, hold_idx: slice, baseline: tuple, seed: int) -> LinkData:
    """`d` with the rate convention of its exact drive that the held-out part prefers: the central difference
    of the catalogue's array forms, the backward one of a per-sample simulation (at a reversal they differ
    by one sample, and an operator's tremor reverses a command hundreds of times), or the drive's rate at the
    sample, its turns placed between samples (`links.exact_turn_rate`: a recording of a continuous drive,
    whose friction switched when the drive turned; tried where its signs differ from the central
    difference's). The probe: the baseline with the simplest rate law on it (Rules.rate_probe: Coulomb
    friction), fitted each way; a tie keeps the earlier convention."""
    best, pick = math.inf, d
    cands = [d, dataclasses.replace(d, backward=True, cache={})]
    located = exact_turn_rate(d.x, d.t)
    if located is not None:   # the rate at each sample, its turns placed between samples (links.exact_turn_rate)
        cands.append(dataclasses.replace(d, v=located, cache={}))
    for cand in cands:
        base = simulation_baseline(cand, fit_idx, hold_idx, baseline, seed)
        try:
            r = fit_chain(cand, base.model, RATE_PROBE, fit_idx, hold_idx, seed=seed).rmse_hold
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            r = base.rmse_hold
        if r < best:
            best, pick = r, cand
    return pick


def _drive_rate(d: LinkData) -> str:
    """How the link's drive rate was taken (links.clean_motion; a noisy drive's turns: links.located_rate)."""
    if d.v is not None and is_exact(d.x) and (located := exact_turn_rate(d.x, d.t)) is not None and np.array_equal(
            located, d.v):   # a noisy drive's smoothed position may pass as exact: its rate is links.located_rate's
        return "turns located (exact drive)"
    if d.v is not None or not is_exact(d.x):
        return "central, smoothed"
    return "backward (exact drive)" if d.backward else "central (exact drive)"


def diagnose(rec: Recording, holdout: float = HOLDOUT, progress=None, seed: int = 0,
             baseline: tuple = PROJECT_BASELINE, sindy: bool = False) -> Diagnosis:
    """Diagnose `rec` beyond the `baseline` simulation (see the module docstring); progress(k) is called
    as candidate fits finish; seed drives the extra starts of multi-start fits (the report is reproducible
    for a given seed). A sensor effect found on a channel is taken out of that channel where a later link
    uses it as its input (a tip force sensor's drift is not the sheath's friction). sindy: also score the
    PySINDy peer (teleop.diagnosis.sindy_peer) beside the ARX one."""
    fit_idx, hold_idx = split(rec.n, holdout)
    results, peer, corrections = [], {}, {}

    def identify(data, bar=None) -> LinkResult:
        return identify_link(data, fit_idx, hold_idx, progress=bar, seed=seed, baseline=tuple(baseline))

    for link in find_links(rec):
        d = link_data(rec, link, corrections)
        res = None   # the identified d, where the choice of input already made it
        used = {link.input, link.load, link.drive} & set(corrections)
        if used:
            # a correction found on another link must make this one's baseline fit better, or it was that
            # link's misfit (a stiffening spring read as a sensor hysteresis), not its sensor's; or, where
            # the baseline alone fits the uncorrected input better, this link's identified fit (a tip
            # sensor's hysteresis beside a Dahl friction: the capstan alone takes the one for the other)
            plain = link_data(rec, link)
            with_c = simulation_baseline(d, fit_idx, hold_idx, tuple(baseline), seed)
            without = simulation_baseline(plain, fit_idx, hold_idx, tuple(baseline), seed)
            if without.rmse_hold <= with_c.rmse_hold:
                res_plain, res = identify(plain), identify(d, progress)
                if res_plain.final.rmse_hold <= res.final.rmse_hold:
                    d, res = plain, res_plain
        if link.kind == "force" and link.drive and d.v is None and is_exact(d.x):   # d.v: a noisy drive
            d, res = exact_rate(d, fit_idx, hold_idx, tuple(baseline), seed), None
        if res is None:
            res = identify(d, progress)
        sharp = [n for n in res.final.names if get_effect(n).rules.raw_input]
        if link.kind == "position" and sharp and not is_exact(rec.channels[link.input]):
            # a play seen on the raw input too: keep whichever input the held-out part prefers (an exact
            # input is not smoothed: its raw form is the same)
            d_raw = link_data(rec, link, corrections, raw_input=True)
            raw = identify(d_raw)
            if raw.final.rmse_hold < res.final.rmse_hold and set(sharp) & set(raw.final.names):
                d, res = d_raw, raw
        results.append(res)
        corr = sensor_correction(res)
        if corr is not None:
            corrections[link.output] = corr
        elif res.delay:   # the channel lags its link's input: read it tau later where it is an input
            y = rec.channels[link.output]
            corrections[link.output] = y - np.interp(rec.t + res.delay[0], rec.t, y)
        peer[link.output] = {"arx_rmse": arx_rmse(d, fit_idx, hold_idx),
                             "baseline_rmse": res.baseline.rmse_hold, "model_rmse": res.final.rmse_hold}
        if sindy:   # the generic sparse-regression peer (PySINDy), same split
            s = sindy_rmse(d, fit_idx, hold_idx)
            peer[link.output].update({"sindy_static_rmse": s["static"], "sindy_free_run_rmse": s["free_run"],
                                      "sindy_rmse": s["best"], "sindy_choice": s["choice"]})
    return Diagnosis(rec, holdout, tuple(results), peer, tuple(baseline))
