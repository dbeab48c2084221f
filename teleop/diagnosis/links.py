"""A recording's links: which links it holds, their data (smoothed inputs, known parameters) and their baseline fit.

The link model itself (Link, LinkData, LinkModel, the effect chain and its prediction) is
teleop.core.physics.links, shared with the simulation and the estimator.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import savgol_coeffs, savgol_filter

from teleop.core.errors import InputError
from teleop.core.physics.base import REGISTRY, get_effect, moves
from teleop.core.physics.links import Link, LinkData, LinkModel, clean_motion, is_exact, noise_sigma
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


INPUT_WIDTHS = 12   # candidate widths of an input's smoothing, geometric from 3 samples to SMOOTH_MAX_S


def smooth_input(x: np.ndarray, dt: float) -> tuple[np.ndarray, int]:
    """(smoothed x, width [samples]) for a position link's input, which the tip follows by its value: of the
    raw samples and the local-line (`smooth`) and local-quadratic (Savitzky-Golay, degree 2) smoothings of
    odd widths up to SMOOTH_MAX_S, the one with the least mean squared error, estimated by leave-one-out
    cross-validation on the interior samples (a linear smoother's leave-one-out residual is (x - s) / (1 -
    h0), h0 its centre weight; its mean square is the noise variance plus the smoothing's squared error; the
    raw samples' error is the noise variance, `noise_sigma`). A local line biases a curved input by about
    (w dt)^2 / 24 times its curvature, which a fast drive read by an exact encoder passes to the tip far
    above the encoder's noise; a local quadratic has no such term, at 2.25 times the line's noise variance
    at one width. An exact signal is not smoothed. The estimate assumes white noise: a sensor whose noise is
    correlated over many samples would be smoothed too little, so loads and force inputs keep `smooth_width`'s
    rate-noise width."""
    n = x.shape[0]
    if is_exact(x) or n < 32:
        return x, 1
    sigma2 = noise_sigma(x) ** 2
    hi = max(5, int(round(SMOOTH_MAX_S / dt)))
    best, out, width = sigma2, x, 1
    for w in sorted({int(v) | 1 for v in np.geomspace(3, hi, INPUT_WIDTHS)}):
        half = w // 2
        if w > n // 4:
            break
        cands = [(smooth(x, w), 1.0 / w)]
        if w >= 5:
            cands.append((savgol_filter(x, w, 2, mode="interp"), float(savgol_coeffs(w, 2)[half])))
        for s, h0 in cands:
            r = (x - s)[half:n - half] / (1.0 - h0)
            err = float(np.mean(r * r)) - sigma2
            if err < best:
                best, out, width = err, s, w
    return out, width


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


TURN_HYSTERESIS = 4.0   # a noisy drive turns once it is back this many of its smoothed noise's sigmas from an extreme
TURN_MAX_S = 0.15       # widest half window [s] of a turn's local fit
TURN_LACK = 9.2         # lack of fit (chi-square, 2 dof, 1 %) that ends the growth of a turn's window
TURN_REST = 3.0         # a sample within this many of its turn's standard errors is at rest there,
REST_MAX = 0.05         # and within this fraction of a sample of it


def _turn_extremes(xs: np.ndarray, h: float) -> tuple[np.ndarray, float]:
    """(indices of the extremes of xs at which it turns, the direction (+1, -1) before the first): the last
    extreme before xs comes back by more than h (a play of half-width h on the drive: the smoothed noise's
    flicker about a slow turn is no turn)."""
    n = xs.shape[0]
    s = 1.0 if xs[min(n - 1, 50)] >= xs[0] else -1.0
    first, ext, ie, out = s, float(xs[0]) if n else 0.0, 0, []
    for i, xi in enumerate(xs.tolist()):
        if s * (xi - ext) > 0.0:
            ext, ie = xi, i
        elif s * (ext - xi) > h:
            if not out:
                first = s
            out.append(ie)
            s, ext, ie = -s, xi, i
    return np.asarray(out, dtype=int), first


def _fit_turn(x: np.ndarray, tau: np.ndarray, deg: int) -> tuple[np.ndarray, float]:
    """(polynomial coefficients in tau, residual sum of squares) of x (m,) on tau (m,)."""
    p = np.polynomial.polynomial.polyfit(tau, x, deg)
    r = np.polynomial.polynomial.polyval(tau, p) - x
    return p, float(np.dot(r, r))


def _vertex(p: np.ndarray) -> float:
    """The stationary point of polynomial p (coefficients, increasing powers) nearest 0, or NaN."""
    r = np.roots(np.polynomial.polynomial.polyder(p)[::-1])
    r = r[np.abs(r.imag) < 1e-12].real
    return float(r[np.argmin(np.abs(r))]) if r.size else math.nan


def _window(t: np.ndarray, tc: float, W: int) -> tuple[slice, np.ndarray]:
    """(the samples within W of the time tc, their times from tc in units of W samples)."""
    dt = float(t[1] - t[0])
    c = int(round((tc - t[0]) / dt))
    sl = slice(max(c - W, 0), min(c + W + 1, t.size))
    return sl, (t[sl] - tc) / (W * dt)


def _locate(x: np.ndarray, t: np.ndarray, tc: float, W: int, deg: int, sigma: float) -> tuple[float, float]:
    """(time [s] of the stationary point of a degree-deg polynomial fitted to x within W samples of it, its
    standard error [s]), starting from tc and re-centred once; (NaN, inf) where none lies in the window."""
    dt = float(t[1] - t[0])
    for _ in range(2):
        sl, tau = _window(t, tc, W)
        r = _vertex(_fit_turn(x[sl], tau, deg)[0])
        if not abs(r) < 0.5:
            return math.nan, math.inf
        tc += r * W * dt
    # the standard error: the fitted slope's at the turn over the curvature
    sl, tau = _window(t, tc, W)
    X = np.vander(tau, deg + 1, increasing=True)
    p = _fit_turn(x[sl], tau, deg)[0]
    se = sigma * math.sqrt(max(float(np.linalg.pinv(X.T @ X)[1, 1]), 0.0))
    return tc, se / max(abs(2.0 * p[2]), 1e-300) * W * dt


KINK_DEGREE = 4       # the jerk-limited turn's pieces: powers 3 .. KINK_DEGREE of the time from the turn
KINK_S = 0.1          # half window [s] of its fit
KINK_SEARCH = 20      # its time is searched within this many samples of the smooth fit's


def _kink_basis(tau: np.ndarray, hi: int) -> np.ndarray:
    """(m, 1 + 2 (hi - 2)) the jerk-limited turn's columns at times tau from it: 1, then (-tau)_+^k and
    tau_+^k for k = 3 .. hi (each leg its own curve, rate and its rate of change zero at the turn)."""
    left, right = np.maximum(-tau, 0.0), np.maximum(tau, 0.0)
    return np.column_stack([np.ones_like(tau)] + [left ** k for k in range(3, hi + 1)]
                           + [right ** k for k in range(3, hi + 1)])


def _kink_rss(x: np.ndarray, t: np.ndarray, tc: float, W: int, hi: int) -> float:
    """Residual sum of squares of the jerk-limited turn at time tc fitted to x within W samples of it."""
    sl, tau = _window(t, tc, W)
    A = _kink_basis(tau, hi)
    p = np.linalg.lstsq(A, x[sl], rcond=None)[0]
    r = A @ p - x[sl]
    return float(np.dot(r, r))


def _locate_kink(x: np.ndarray, t: np.ndarray, tc: float, cap: int, sigma: float) -> tuple[float, float, float]:
    """(time [s], standard error [s], the fit's gain over a smooth quintic [chi-square]) of a jerk-limited turn
    near tc: the rate rises from it as the square of the time, each leg at its own rate (an S-curve motion
    profile's stop, a rounded triangle), so its drive has a kink in the third derivative no polynomial
    follows, and a smooth fit's stationary point misplaces it by milliseconds. The pieces of degree
    KINK_DEGREE are fitted over KINK_S (at most cap samples) on either side; the time is where their residual
    is least (grids of narrowing span from KINK_SEARCH samples about tc, then a parabola through the least
    three); the gain is a smooth quintic's residual there less the turn's, over the noise's variance (the same
    number of coefficients)."""
    dt = float(t[1] - t[0])
    W = int(min(cap, KINK_S / dt))
    if W < 8:
        return math.nan, math.inf, -math.inf
    best, se = tc, dt
    for span in (KINK_SEARCH * dt, 2.0 * dt, 0.2 * dt, 0.02 * dt):
        grid = best + np.linspace(-span, span, 21)
        f = np.array([_kink_rss(x, t, g, W, KINK_DEGREE) for g in grid])
        if span == 2.0 * dt:
            # the standard error from the residual's curvature in the time over +-2 samples (finer, the knot
            # crossing each sample makes it rough): RSS(t) ~ RSS_min + sigma^2 (t - t_min)^2 / se^2
            c2 = float(np.polyfit((grid - best) / dt, f, 2)[0])
            se = sigma * dt / math.sqrt(c2) if c2 > 0 else dt
        i = int(np.clip(np.argmin(f), 1, grid.size - 2))
        best = float(grid[i])
    h = float(grid[1] - grid[0])
    den = f[i + 1] - 2.0 * f[i] + f[i - 1]
    if den > 0:
        best += 0.5 * h * (f[i - 1] - f[i + 1]) / den
    sl, tau = _window(t, best, W)
    return best, se, (_fit_turn(x[sl], tau, 5)[1] - _kink_rss(x, t, best, W, KINK_DEGREE)) / (sigma * sigma)


def turn_times(x: np.ndarray, t: np.ndarray, xs: np.ndarray, sigma: float,
               width: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(times [s] of a noisy drive's turns, each located between samples; their standard errors [s]; the
    direction before the first). The turns are the extremes of the smoothed drive xs that it leaves by
    TURN_HYSTERESIS of its noise (sigma / sqrt(width), sigma x's); each is located on
    the recorded drive x by the stationary point of a local polynomial, whose half window grows (up to
    TURN_MAX_S and half the way to the next turns) while a cubic still fits it (against a quintic: TURN_LACK).
    Where the cubic's own term is within the noise the turn is symmetric and a parabola over twice that window
    locates it (a cubic's third-order term costs the vertex 2.5x its precision). An instant switch at a turn
    costs the whole friction band at each sample put on the wrong side, so the turn must be placed to a small
    fraction of a sample, which the smoothed rate's sign does not do (its moving average and central
    difference leave the turn's time to within about a quarter of a sample)."""
    ext, first = _turn_extremes(xs, TURN_HYSTERESIS * sigma / math.sqrt(max(width, 1)))
    dt = float(np.median(np.diff(t)))
    out, err = np.empty(ext.size), np.zeros(ext.size)
    for j, e in enumerate(ext):
        gap = min(e - (ext[j - 1] if j else 0), (ext[j + 1] if j + 1 < ext.size else t.size - 1) - e)
        cap = int(min(0.5 * gap, TURN_MAX_S / dt))
        out[j], err[j] = t[e], dt   # where it cannot be located: at the extreme, to within a sample
        if cap < 4:
            continue
        W = None
        for w in np.unique(np.geomspace(4, cap, 10).astype(int)):
            sl, tau = _window(t, float(t[e]), int(w))
            if W is not None and (_fit_turn(x[sl], tau, 3)[1] - _fit_turn(x[sl], tau, 5)[1]) / (
                    2.0 * sigma * sigma) > TURN_LACK:
                break
            W = int(w)
        tc, sd = _locate(x, t, float(t[e]), W, 3, sigma)
        if not math.isfinite(tc):
            continue
        # a parabola over twice the window where the cubic's term is within 3 standard errors there (centred
        # on the turn: off it, a quartic term shows as a cubic one)
        W2 = min(2 * W, cap)
        sl, tau = _window(t, tc, W2)
        X = np.vander(tau, 4, increasing=True)
        p3 = _fit_turn(x[sl], tau, 3)[0][3]
        if abs(p3) <= 3.0 * sigma * math.sqrt(max(float(np.linalg.pinv(X.T @ X)[3, 3]), 0.0)):
            t2, sd2 = _locate(x, t, tc, W2, 2, sigma)
            if math.isfinite(t2):
                tc, sd = t2, sd2
        # a jerk-limited turn (the rate rising as the square of the time from it, each leg its own way):
        # where its pieces fit better than a smooth quintic by more than TURN_LACK, they place it
        tk, sk, gain = _locate_kink(x, t, tc, cap, sigma)
        if math.isfinite(tk) and gain > TURN_LACK and abs(tk - float(t[e])) < 0.5 * cap * dt:
            tc, sd = tk, sk
        out[j], err[j] = tc, sd
    return out, err, first


EXACT_LEG = 6        # samples on each side of an exact drive's extreme whose interpolant is extrapolated to it
EXACT_CLEAR = 0.1    # one side's extrapolation error below this fraction of the other's: the extreme is on it
EXACT_REST = 1e-6    # a joint interpolant's rate at the extreme below this fraction of the legs' mean rate: rest


def exact_turn_rate(x: np.ndarray, t: np.ndarray) -> np.ndarray | None:
    """(n,) the rate [x's unit/s] of an exact drive x (n,) with the sign at each strict extreme sample set by
    where the turn lies, or None where that changes no sign of the central difference. At a turn the extreme
    sample is the only one whose side is in doubt (the turn lies within a sample of it); the central
    difference takes it from the two neighbours, right for a turn symmetric to second order, wrong by up to
    a sample where the legs differ (a drive whose speed rises from the turn as a power of the time, faster
    one way than the other). Here the interpolant of EXACT_LEG samples of each leg is extrapolated to the
    extreme: a sample on one leg's own curve (the other's error above 1 / EXACT_CLEAR of it) lies on that
    side of the turn; where both legs reach it alike (a smooth turn) the sign is that of the rate of the
    joint interpolant of the five samples about it, 0 (at rest) where that is within EXACT_REST of the legs'
    rate. The magnitude stays the central difference's. Legs that are not monotone over EXACT_LEG samples
    (an operator's tremor) keep the central difference."""
    n, m = x.shape[0], EXACT_LEG
    v = np.gradient(x, t)
    dx = np.diff(x)
    out = v.copy()
    for j in (np.flatnonzero(dx[:-1] * dx[1:] < 0) + 1).tolist():
        if j < m or j + m >= n:
            continue
        left, right = dx[j - m:j], dx[j:j + m]
        if np.any(left * dx[j - 1] <= 0) or np.any(right * dx[j] <= 0):
            continue
        tau = (t[j - m:j + m + 1] - t[j]) / (t[j] - t[j - 1])
        xc = x[j - m:j + m + 1] - x[j]
        e_left = abs(float(np.polyval(np.polyfit(tau[:m], xc[:m], m - 1), 0.0)))
        e_right = abs(float(np.polyval(np.polyfit(tau[m + 1:], xc[m + 1:], m - 1), 0.0)))
        new = math.copysign(1.0, dx[j])
        if min(e_left, e_right) < EXACT_CLEAR * max(e_left, e_right):
            s = -new if e_left < e_right else new
        else:
            mid = slice(m - 2, m + 3)
            rate = float(np.polyval(np.polyder(np.polyfit(tau[mid], xc[mid], 4)), 0.0))
            leg = 0.5 * (abs(float(np.mean(left))) + abs(float(np.mean(right))))
            s = 0.0 if abs(rate) <= EXACT_REST * leg else math.copysign(1.0, rate)
        mag = abs(v[j]) if v[j] != 0.0 else 0.5 * abs(dx[j]) / float(t[j + 1] - t[j])
        out[j] = s * mag
    return None if np.array_equal(np.sign(out), np.sign(v)) else out


STOP_QUANTA = 8.0   # a lattice drive held on one reading for more than this many times its time per count on
                    # either side has stopped (a smooth turn holds its extreme reading 1.4-5x as long as its
                    # neighbours, a pause before a stroke's turn tens of times)


def lattice_stops(x: np.ndarray) -> np.ndarray:
    """(n,) True on the samples of a drive x (n,) read on an encoder's lattice that lie in a stop: a run of at
    least 3 equal readings longer than STOP_QUANTA times the time per count of the runs either side of it
    (the count over their length: the speed entering and leaving it, the slower of the two). The smoothed
    drive's rate moves through such a run (half a smoothing width into each end, round-off with a sign
    between), where the catalogue's rate laws would read motion and a Stribeck friction its breakaway peak.
    A noisy drive seldom repeats a reading: none. The first and last runs of the record are not judged."""
    n = x.shape[0]
    dx = np.diff(x)
    moved = moves(x)
    out = np.zeros(n, dtype=bool)
    if moved.size == 0:
        return out
    q = float(moved.min())   # the lattice's count (as noise_sigma reads it)
    start = np.flatnonzero(np.r_[True, dx != 0])          # first sample of each run of equal readings
    length = np.diff(np.r_[start, n])
    if start.size < 4:
        return out
    i = np.arange(1, start.size - 2)
    v_in = np.abs(x[start[i]] - x[start[i - 1]]) / length[i - 1]
    v_out = np.abs(x[start[i + 2]] - x[start[i + 1]]) / length[i + 1]
    v = np.minimum(v_in, v_out)
    stop = i[(v > 0) & (length[i] >= 3) & (length[i] > STOP_QUANTA * q / np.maximum(v, 1e-300))]
    for j in stop.tolist():
        out[start[j]:start[j] + length[j]] = True
    return out


def located_rate(x: np.ndarray, t: np.ndarray, xs: np.ndarray, width: int) -> np.ndarray:
    """(n,) the rate of a noisy drive x (n,) (smoothed: xs, `smooth` of width) with its direction switched at
    its located turns (`turn_times`): the smoothed rate's magnitude, 0 where links.clean_motion or, on an
    encoder's lattice, `lattice_stops` finds a stop,
    and between turns the sign of the stretch (a sample at t after a turn at t0 < t moves the new way). A
    sample within TURN_REST standard errors of a turn (and within REST_MAX of a sample) is at rest (0: the
    drive's rate there is zero within what the recording resolves, and the catalogue's rate laws hold their
    state)."""
    _, vc = clean_motion(xs, t)
    turns, err, first = turn_times(x, t, xs, noise_sigma(x), width)
    if not turns.size:
        return vc
    leg = np.searchsorted(turns, t, side="left")   # the stretch each sample lies in (after leg turns)
    sign = np.where(leg % 2 == 0, first, -first)
    near = np.clip(np.searchsorted(turns, t), 1, turns.size) - 1
    near = np.where(np.abs(turns[np.minimum(near + 1, turns.size - 1)] - t) < np.abs(turns[near] - t),
                    np.minimum(near + 1, turns.size - 1), near)
    rest = np.abs(t - turns[near]) <= np.minimum(TURN_REST * err[near], REST_MAX * float(np.median(np.diff(t))))
    return np.where((vc == 0.0) | rest | lattice_stops(x), 0.0, sign * np.abs(vc))


RATE_MEMO = 4    # link_data's memo of the noisy drives' located rates (the last this many drives)
_RATES: list = []


def _shared_rate(x: np.ndarray, t: np.ndarray, xs: np.ndarray, width: int) -> np.ndarray:
    """`located_rate`(x, t, xs, width) (xs: x smoothed over width), memoised on the recorded drive's samples:
    the links of a recording that share a drive (the spring law's and the force link's motor position) and
    a link read twice (with and without a correction of another channel) locate its turns once. Read-only."""
    for x0, t0, w0, v in _RATES:
        if w0 == width and x0.shape == x.shape and np.array_equal(x0, x) and np.array_equal(t0, t):
            return v
    v = located_rate(x, t, xs, width)
    v.flags.writeable = False
    _RATES.insert(0, (x.copy(), t.copy(), width, v))
    del _RATES[RATE_MEMO:]
    return v


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
    v = None
    if x is not None and widths[-1] > 1:   # a noisy drive: its turns located between samples
        v = _shared_rate(ch[link.drive], rec.t, x, widths[-1])

    def sm_input(name):
        s, w = smooth_input(ch[name], dt)
        widths.append(w)
        return s

    # a position link's input by the least-error smoothing (the tip follows its value); others by the rate rule
    u = ch[link.input] if raw_input else (sm_input(link.input) if link.kind == "position" else sm(link.input))
    load = sm(link.load) if link.load else None
    temp = sm("temperature") if "temperature" in ch else None
    return LinkData(link, rec.t, u, ch[link.output], x, load, temp, ch.get("bend_angle"), max(widths) * dt,
                    known_params(rec), v=v)


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
