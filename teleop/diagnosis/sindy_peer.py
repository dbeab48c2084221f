"""A generic sparse-regression peer: PySINDy's libraries, derivative and STLSQ optimiser, its model chosen on
a validation part of the fit part and scored on the same held-out split as the physics.

Two forms, each fitted on the fit part and scored on the held-out part (`sindy_rmse` reports both and the
better one: the physics must beat both):

- static: y = Theta(z) xi, z = the link's inputs (input, the drive's rate scaled to its 99th percentile and
  the rate's sign, the drive position where it is not the input, the load, temperature, bend) standardised
  on the fit part, Theta = pysindy's PolynomialLibrary (degree 1-3) + FourierLibrary; a memoryless map, the
  regression a user would try first.
- free run: a state model of the standardised output s, Theta(s, z) = PolynomialLibrary (degree 1-3) of the
  output and the inputs, either discrete, s_k+1 = Theta(s_k, z_k) xi, or continuous, ds/dt = Theta(s, z) xi
  (the rate by pysindy's FiniteDifference, stepped by explicit Euler); run from the measured output at the
  held-out start with the recorded inputs: an output-error score like the physics models'.

Model choice (never on the held-out part): the fit part's last VALIDATION fraction validates; every degree
in DEGREES and STLSQ threshold in THRESHOLDS (and, free run, both forms) is fitted on the part before it (the
training part) and scored there (the free run from the measured output at the validation start). The static
choice is then refitted on the whole fit part; the free run keeps the validated model itself (a state model
refitted on more data can lose the stability its validation showed). Extrapolation is guarded: a free run
clips its inputs and state to the ranges its training part spans; the static form's guard is validated too,
either that clip or the clip continued linearly past the ranges by the best-validated degree-1 model's
change (a linear law extrapolates linearly, a cubic does not). `choice` reports the form, degree, threshold, guard, number of
terms and validation RMSE [output units].

Hand-written beside pysindy, and why: the validation split and the extrapolation guard (pysindy has no
model selection of its own; its sklearn route, GridSearchCV, scores the derivative's fit, not an output
error), and the free run's stepping (pysindy's DiscreteSINDy.simulate and SINDy.simulate neither clip nor
run fast enough: a one-row library transform costs milliseconds, so a step evaluates the fitted library's
own monomials, `PolynomialLibrary.powers_`, in numpy). Fitting runs at about peer.PEER_HZ (the peer sees the
same samples, decimated); the static form is scored on every held-out sample.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from teleop.core.physics.links import LinkData
from teleop.diagnosis.peer import PEER_HZ

DEGREES = (1, 2, 3)                                     # polynomial library degrees tried
THRESHOLDS = (0.0, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3)    # STLSQ thresholds (standardised features and output)
VALIDATION = 0.25    # the free run: the fit part's last quarter validates the choice
FOLDS = 4            # the static form: cross-validation over the fit part in this many folds, each
BLOCKS_PER_FOLD = 16  # this many contiguous blocks spread over the fit part
ALPHA = 1e-6         # STLSQ's ridge weight (standardised units): only breaks exact ties (sign(v)^2 = 1)
FORMS = ("discrete", "continuous")


def _inputs(d: LinkData) -> tuple[np.ndarray, list[str]]:
    """The link's input columns (n, m) and their names."""
    cols, names = [d.u], ["u"]
    x, v = d.motion()
    if x is not None:
        scale = max(float(np.percentile(np.abs(v), 99)), 1e-300)
        cols += [v / scale, np.sign(v)]
        names += ["v", "sign_v"]
        if d.link.input != d.link.drive:
            cols.append(x)
            names.append("x")
    if d.load is not None and d.link.load != d.link.input:
        cols.append(d.load)
        names.append("load")
    for name in ("temperature", "theta"):
        a = getattr(d, name)
        if a is not None and float(np.ptp(a)) > 0:
            cols.append(a)
            names.append(name)
    return np.column_stack(cols), names


@dataclass(frozen=True)
class _Scale:
    """Standardisation fitted on some rows: z = (w - mean) / sd, and the z range those rows span."""

    mean: np.ndarray
    sd: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def of(cls, W: np.ndarray) -> "_Scale":
        mean, sd = W.mean(0), W.std(0)
        sd = np.where(sd > 0, sd, 1.0)
        Z = (W - mean) / sd
        return cls(mean, sd, Z.min(0), Z.max(0))

    def z(self, W: np.ndarray) -> np.ndarray:
        return (W - self.mean) / self.sd

    def clip(self, Z: np.ndarray) -> np.ndarray:
        return np.clip(Z, self.lo, self.hi)

    def outside(self, Z: np.ndarray) -> np.ndarray:
        return np.any((Z < self.lo) | (Z > self.hi), axis=1)


def _static_library(degree: int):
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)
    return ps.PolynomialLibrary(degree=degree) + ps.FourierLibrary(n_frequencies=1)


def _poly_library(degree: int):
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)
    return ps.PolynomialLibrary(degree=degree)


def _stlsq(T: np.ndarray, target: np.ndarray, threshold: float) -> np.ndarray:
    """Sparse coefficients (n_features,) of target ~ T xi by pysindy's STLSQ."""
    import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)

    opt = ps.STLSQ(threshold=threshold, alpha=ALPHA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        opt.fit(T, target[:, None])
    return np.asarray(opt.coef_, dtype=float)[0]


def _rms(r: np.ndarray) -> float:
    """RMS of r; inf where r is empty or not finite (a diverging candidate)."""
    v = float(np.sqrt(np.mean(r * r))) if r.size else math.inf
    return v if math.isfinite(v) else math.inf


def _stride(d: LinkData) -> int:
    return max(1, int(round(1.0 / (PEER_HZ * float(np.median(np.diff(d.t)))))))


def _parts(d: LinkData, fit_idx: slice) -> tuple[np.ndarray, int, int]:
    """(idx, k_train, k_fit): the decimated sample indices, and where in them the validation part and the
    held-out part start (the fit part is idx[:k_fit], its training part idx[:k_train])."""
    idx = np.arange(0, d.n, _stride(d))
    k_fit = int(np.searchsorted(idx, fit_idx.stop))
    k_train = int(round(k_fit * (1.0 - VALIDATION)))
    return idx, k_train, k_fit


class _Static:
    """The static form fitted on rows `rows` of (W, y) at each (degree, threshold) of `keys` (all by
    default), predicting any rows."""

    def __init__(self, W: np.ndarray, y: np.ndarray, rows: np.ndarray, keys=None):
        keys = set(keys or [(deg, thr) for deg in DEGREES for thr in THRESHOLDS])
        self.scale = _Scale.of(W[rows])
        self.ym, self.ysd = float(np.mean(y[rows])), max(float(np.std(y[rows])), 1e-300)
        self.libs, self.coefs = {}, {}
        Z = self.scale.z(W[rows])
        target = (y[rows] - self.ym) / self.ysd
        for deg in sorted({k[0] for k in keys}):
            lib = _static_library(deg)
            lib.fit(Z)
            T = np.asarray(lib.transform(Z))
            self.libs[deg] = lib
            for thr in sorted(k[1] for k in keys if k[0] == deg):
                self.coefs[deg, thr] = _stlsq(T, target, thr)

    def predict(self, W: np.ndarray, clip: bool) -> dict:
        """{(degree, threshold): prediction (n,)} in output units, the inputs clipped or not."""
        Z = self.scale.z(W)
        if clip:
            Z = self.scale.clip(Z)
        out = {}
        for deg, lib in self.libs.items():
            T = np.asarray(lib.transform(Z))
            for (dg, thr), c in self.coefs.items():
                if dg == deg:
                    out[deg, thr] = self.ym + self.ysd * (T @ c)
        return out


def _static_guarded(model: _Static, W: np.ndarray, fallback_thr: float) -> dict:
    """{(degree, threshold, guard): prediction}: guard "clip" (the inputs clipped to the fitted ranges) and
    "linear" (that, continued past the ranges by the degree-1 model at fallback_thr: plus its change from
    the clipped inputs to the actual ones; the same inside the ranges)."""
    clipped, raw = model.predict(W, True), model.predict(W, False)
    beyond = raw[1, fallback_thr] - clipped[1, fallback_thr]
    out = {}
    for (deg, thr), p in clipped.items():
        out[deg, thr, "clip"] = p
        out[deg, thr, "linear"] = p + beyond
    return out


def static_fit(d: LinkData, fit_idx: slice, hold_idx: slice) -> tuple[float, dict]:
    """(held-out RMSE in output units, choice) of the static sparse regression, its degree, threshold and
    guard chosen by cross-validation within the fit part: FOLDS folds of BLOCKS_PER_FOLD contiguous blocks
    spread over it, each fold validating a model fitted on the others; the median of the folds' RMSEs
    decides (one fold holding an unrepresentative stretch, such as a start from rest, does not)."""
    W, _ = _inputs(d)
    idx, _, k_fit = _parts(d, fit_idx)
    fit = idx[:k_fit]
    blocks = np.array_split(np.arange(k_fit), FOLDS * BLOCKS_PER_FOLD)
    folds = []
    for j in range(FOLDS):
        block = np.concatenate(blocks[j::FOLDS])
        m = _Static(W, d.y, np.delete(fit, block))
        folds.append((m, fit[block], m.predict(W[fit[block]], False)))

    def pooled(preds):   # {key: [prediction per fold]} -> {key: the median over the folds of their RMSE}
        return {k: float(np.median([_rms(p - d.y[val]) for p, (_, val, _) in zip(ps, folds)]))
                for k, ps in preds.items()}

    lin = pooled({thr: [raw[1, thr] for _, _, raw in folds] for thr in THRESHOLDS})
    lin_thr = min(lin, key=lin.get)
    guarded = [_static_guarded(m, W[val], lin_thr) for m, val, _ in folds]
    scores = pooled({k: [g[k] for g in guarded] for k in guarded[0]})
    deg, thr, guard = min(scores, key=scores.get)
    full = _Static(W, d.y, fit, [(deg, thr), (1, lin_thr)])
    pred = _static_guarded(full, W[hold_idx], lin_thr)[deg, thr, guard]
    choice = {"degree": deg, "threshold": thr, "guard": "none" if (deg, guard) == (1, "linear") else guard,
              "terms": int(np.count_nonzero(full.coefs[deg, thr])), "validation_rmse": scores[deg, thr, guard]}
    return _rms(pred - d.y[hold_idx]), choice


def _monomials(V: np.ndarray, powers: np.ndarray) -> np.ndarray:
    """The PolynomialLibrary's features of rows V (r, m): prod_j V_j ** powers_ij, (r, n_features)."""
    return np.prod(V[:, None, :] ** powers[None, :, :], axis=2)


class _FreeRun:
    """The free-run form fitted on decimated steps [0, k) of (s, Z) at every form, degree and threshold;
    `run` steps them all at once."""

    def __init__(self, s: np.ndarray, Z: np.ndarray, t: np.ndarray, k: int, s_range: tuple, z_scale: _Scale):
        import pysindy as ps  # heavy: loaded only for the sparse-regression peer (diagnose --sindy)

        self.h = float(np.median(np.diff(t[:k])))
        self.s_range, self.z_scale = s_range, z_scale
        V = np.column_stack([s[:k], Z[:k]])
        rate = np.asarray(ps.FiniteDifference()(s[:k, None], t[:k]))[:, 0]
        self.powers, self.coefs = {}, {}
        for deg in DEGREES:
            lib = _poly_library(deg)
            lib.fit(V)
            T = np.asarray(lib.transform(V))
            self.powers[deg] = np.asarray(lib.powers_)
            for thr in THRESHOLDS:
                self.coefs["discrete", deg, thr] = _stlsq(T[:-1], s[1:k], thr)
                self.coefs["continuous", deg, thr] = _stlsq(T, rate, thr)

    def run(self, s0: float, Z: np.ndarray) -> dict:
        """{(form, degree, threshold): s over len(Z) steps}, step j from the previous state (s0 before the
        first) and Z[j], inputs and state clipped to the fitted ranges."""
        keys = list(self.coefs)
        lo, hi = self.s_range
        Zc = self.z_scale.clip(Z)
        st = np.full(len(keys), s0)
        out = np.empty((Z.shape[0], len(keys)))
        disc = np.array([k[0] == "discrete" for k in keys])
        by_deg = {deg: [i for i, k in enumerate(keys) if k[1] == deg] for deg in self.powers}
        C = {deg: np.array([self.coefs[keys[i]] for i in ii]) for deg, ii in by_deg.items()}
        for j in range(Z.shape[0]):
            V = np.column_stack([st, np.broadcast_to(Zc[j], (st.size, Zc.shape[1]))])
            f = np.empty(st.size)
            for deg, ii in by_deg.items():
                f[ii] = np.einsum("ij,ij->i", _monomials(V[ii], self.powers[deg]), C[deg])
            st = np.clip(np.where(disc, f, st + self.h * f), lo, hi)
            out[j] = st
        return {k: out[:, i] for i, k in enumerate(keys)}


def free_run_fit(d: LinkData, fit_idx: slice, hold_idx: slice) -> tuple[float, dict]:
    """(held-out RMSE in output units at the decimated samples, choice) of the free-run state model, its
    form, degree and threshold chosen on the validation part; inf if it cannot be fitted."""
    W, _ = _inputs(d)
    idx, k_train, k_fit = _parts(d, fit_idx)
    if k_train < 8 or k_fit - k_train < 2 or idx.size - k_fit < 1:
        return math.inf, {}
    t, y, Wd = d.t[idx], d.y[idx], W[idx]
    ym, ysd = float(np.mean(y[:k_fit])), max(float(np.std(y[:k_fit])), 1e-300)
    s = (y - ym) / ysd

    sc = _Scale.of(Wd[:k_train])
    m = _FreeRun(s, sc.z(Wd), t, k_train, (float(s[:k_train].min()), float(s[:k_train].max())), sc)
    runs = m.run(float(s[k_train - 1]), sc.z(Wd[k_train - 1:k_fit - 1]))
    # a step's inputs are the row before it: run() steps from s[k-1] with Z[k-1] to s[k]
    scores = {key: _rms(ysd * (r - s[k_train:k_fit])) for key, r in runs.items()}
    scores = {k: v for k, v in scores.items() if math.isfinite(v)}
    if not scores:
        return math.inf, {}
    key = min(scores, key=scores.get)
    # the validated model itself runs the held-out part: a state model refitted on more data can lose the
    # stability its validation showed
    r = m.run(float(s[k_fit - 1]), sc.z(Wd[k_fit - 1:-1]))[key]
    form, deg, thr = key
    choice = {"form": form, "degree": deg, "threshold": thr, "guard": "clip",
              "terms": int(np.count_nonzero(m.coefs[key])), "validation_rmse": scores[key]}
    return _rms(ysd * (r - s[k_fit:])), choice


def static_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out RMSE of the static sparse regression (output units)."""
    return static_fit(d, fit_idx, hold_idx)[0]


def free_run_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> float:
    """Held-out RMSE of the free-run state model (output units); inf if it cannot be fitted."""
    return free_run_fit(d, fit_idx, hold_idx)[0]


def sindy_rmse(d: LinkData, fit_idx: slice, hold_idx: slice) -> dict:
    """{"static", "free_run", "best"} held-out RMSEs of the PySINDy peer (output units; free_run None where
    it could not be fitted) and "choice": {"static": ..., "free_run": ...}, what validation chose."""
    # small least-squares problems: one BLAS thread (threads only contend on a shared machine), and a
    # candidate that overflows validates as inf
    with threadpool_limits(limits=1), np.errstate(over="ignore", invalid="ignore"):
        s, cs = static_fit(d, fit_idx, hold_idx)
        try:
            f, cf = free_run_fit(d, fit_idx, hold_idx)
        except (ValueError, np.linalg.LinAlgError):   # an ill-posed fit is the peer's loss, not an error of ours
            f, cf = math.inf, {}
    return {"static": s, "free_run": f if math.isfinite(f) else None, "best": min(s, f),
            "choice": {"static": cs, "free_run": cf}}
