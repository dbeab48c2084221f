"""Kalman filter on the external wrench (filterpy), its noise model and the steady-state fast form.

Model, per wrench axis k (6 independent axes: Fx, Fy, Fz [N], tx, ty, tz [N m]):
    state x = [w, w_dot]              (2,) wrench component and its rate
    x_k = F x_{k-1} + process noise,  F = [[1, dt], [0, 1]]
    Q = Q_discrete_white_noise(2, dt, q)   piecewise-constant white "force acceleration" of variance q
    z_k = H x_k + v,  H = [1, 0],  R = r  measurement variance
Noise model:
    r_k = (A diag(sigma_t^2) A^T)_kk: the FSR tension noise sigma_t [N] of each cable, independent between
          cables, propagated through f = -A t at the reference pose (home).
    q_k = lambda r_k, with lambda tuned so that the steady-state filter's -3 dB bandwidth equals the expected
          contact-force bandwidth (`bandwidth_hz`: hand palpation changes force over ~0.1 s). The gain depends
          only on q/r, so every axis gets the same bandwidth; the tuning solves for lambda by bisection.
Steady state: the gain K is computed at construction by running filterpy's KalmanFilter recursion until K
stops changing (the Riccati fixed point). Started at that fixed point, filterpy's predict/update produces
exactly the same estimates as the two-line steady-state step used in the hot path (tests check both this and
the convergence of a filter started far away).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter
from scipy.linalg import solve_discrete_are

from teleop.core.geometry import Geometry
from teleop.core.kernels import kalman as KK
from teleop.core.kernels.kalman import kalman_update
from teleop.core.kinematics import structure_matrix


@dataclass(frozen=True)
class KalmanNoise:
    """Noise model of the wrench filter.

    Attributes:
        dt: nominal loop period [s] (the steady-state gain is computed for it).
        bandwidth_hz: -3 dB bandwidth of the steady-state filter [Hz] (expected contact-force bandwidth).
        sigma_t: RMS FSR tension noise per cable [N]: 1 count RMS ADC noise through the default calibration's
            slope is 0.017 N at the 2.85 N pretension (0.008-0.034 N over 0.5-5.5 N,
            teleop.core.sensors.tension_noise): 0.02 N.
    """

    dt: float = 1e-3
    bandwidth_hz: float = 8.0
    sigma_t: float = 0.02

    @classmethod
    def for_loop(cls, params, **kw) -> "KalmanNoise":
        """The noise model of a loop's estimator (teleop.loop.LoopParams `params`): its gain designed for the
        period of the robot frames it sees, one every robot_every ticks of dt: dt * robot_every [s]."""
        return cls(dt=float(params.dt * params.robot_every), **kw)


def axis_matrices(dt: float, q: float, r: float):
    """(F, H, Q, R) of one axis: (2,2), (1,2), (2,2), (1,1)."""
    F = np.array([[1.0, dt], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    Q = Q_discrete_white_noise(dim=2, dt=dt, var=q)
    return F, H, Q, np.array([[r]])


def measurement_variances(geom: Geometry, sigma_t: float, pose=None) -> np.ndarray:
    """(6,) r_k = (A diag(sigma_t^2) A^T)_kk at `pose` (default home) [N^2, (N m)^2], floored at 1e-6 max."""
    A = structure_matrix(np.zeros(6) if pose is None else pose, geom)
    r = (A ** 2).sum(axis=1) * sigma_t ** 2
    # an axis no cable acts on (the moment about the shaft of an axial robot) gets a small floor
    return np.maximum(r, 1e-6 * r.max())


def _dare_gain(dt: float, ratio: float) -> np.ndarray:
    F, H, Q, R = axis_matrices(dt, ratio, 1.0)
    P = solve_discrete_are(F.T, H.T, Q, R)  # prior covariance at the fixed point
    return (P @ H.T / (H @ P @ H.T + R)).ravel()


def bandwidth_hz(K, dt: float) -> float:
    """-3 dB frequency [Hz] of the steady-state filter z -> w with gain K (2,): x_k = (I - K H) F x_{k-1} + K z_k."""
    F, H = np.array([[1.0, dt], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    M = (np.eye(2) - np.outer(K, H)) @ F
    f = np.geomspace(1e-2, 0.5 / dt, 1500)
    zinv = np.exp(-2j * np.pi * f * dt)
    # G(f) = H (I - M z^-1)^-1 K, 2x2 inverse written out
    a, b, c, d = 1 - M[0, 0] * zinv, -M[0, 1] * zinv, -M[1, 0] * zinv, 1 - M[1, 1] * zinv
    det = a * d - b * c
    g = np.abs((d * K[0] - b * K[1]) / det)
    below = np.nonzero(g < 1 / np.sqrt(2))[0]
    return float(f[below[0]]) if below.size else float(f[-1])


@lru_cache(maxsize=32)
def tune_ratio(dt: float, bw_hz: float) -> float:
    """lambda = q / r giving the steady-state -3 dB bandwidth `bw_hz` (bisection in log lambda)."""
    lo, hi = -12.0, 16.0
    for _ in range(36):
        mid = 0.5 * (lo + hi)
        if bandwidth_hz(_dare_gain(dt, 10 ** mid), dt) < bw_hz:
            lo = mid
        else:
            hi = mid
    return 10 ** (0.5 * (lo + hi))


@lru_cache(maxsize=32)
def steady_state(dt: float, q: float, r: float, tol: float = 1e-14, max_iter: int = 200_000):
    """(K (2,), P_post (2,2)) from filterpy's recursion run until the gain stops changing."""
    F, H, Q, R = axis_matrices(dt, q, r)
    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.F, kf.H, kf.Q, kf.R = F, H, Q, R
    kf.P = np.eye(2) * 1e3 * max(r, 1e-12)
    K_prev = np.zeros((2, 1))
    for _ in range(max_iter):
        kf.predict()
        kf.update(np.zeros(1))
        if np.abs(kf.K - K_prev).max() <= tol * np.abs(kf.K).max():
            break
        K_prev = kf.K.copy()
    else:  # pragma: no cover - the recursion always converges for this observable, controllable pair
        raise RuntimeError("Kalman gain did not converge")
    K, P = kf.K.ravel().copy(), kf.P.copy()
    K.setflags(write=False)
    P.setflags(write=False)
    return K, P


@dataclass(frozen=True)
class WrenchKalmanParams:
    """Per-axis filter constants (6 axes).

    Attributes:
        dt: period [s]; r: (6,) measurement variances; q: (6,) process variances; K: (6, 2) steady gains;
        P: (6, 2, 2) steady posterior covariances.
    """

    dt: float
    r: tuple
    q: tuple
    K: tuple
    P: tuple


def wrench_kalman_params(geom: Geometry, noise: KalmanNoise = KalmanNoise()) -> WrenchKalmanParams:
    """The noise model of the module docstring, evaluated for `geom` (home pose)."""
    r = measurement_variances(geom, noise.sigma_t)
    lam = tune_ratio(float(noise.dt), float(noise.bandwidth_hz))
    q = lam * r
    # K depends on q/r only and P scales with r: one filterpy recursion with r = 1 serves all axes
    K, P1 = steady_state(float(noise.dt), lam, 1.0)
    return WrenchKalmanParams(dt=float(noise.dt), r=tuple(map(float, r)), q=tuple(map(float, q)),
                              K=tuple(tuple(map(float, K)) for _ in r),
                              P=tuple(tuple(map(tuple, (P1 * rk).tolist())) for rk in r))


def make_filterpy(params: WrenchKalmanParams, steady: bool = True) -> KalmanFilter:
    """The 12-state filterpy KalmanFilter of all six axes (block diagonal).

    State order [w_1, w_1_dot, ..., w_6, w_6_dot]. steady=True starts P at the steady posterior (then its
    estimates equal `SteadyWrenchKalman`'s), else at a large diagonal.
    """
    kf = KalmanFilter(dim_x=12, dim_z=6)
    F = np.zeros((12, 12))
    H = np.zeros((6, 12))
    Q = np.zeros((12, 12))
    P = np.zeros((12, 12))
    for k in range(6):
        Fk, Hk, Qk, _ = axis_matrices(params.dt, params.q[k], params.r[k])
        s = slice(2 * k, 2 * k + 2)
        F[s, s], H[k, s], Q[s, s] = Fk, Hk, Qk
        P[s, s] = np.array(params.P[k]) if steady else np.eye(2) * 1e3 * params.r[k]
    kf.F, kf.H, kf.Q, kf.R, kf.P = F, H, Q, np.diag(params.r), P
    return kf


class SteadyWrenchKalman:
    """Steady-state wrench filter (the hot path). `update(z)` -> filtered (6,) wrench.

    The step is teleop.core.kernels.kalman.kalman_update (per axis: predict w_p = w + dt w_dot; innovation
    y = z - w_p; w = w_p + K0 y; w_dot = w_dot + K1 y; the first measurement initialises the state to [z, 0])
    on this object's filter array `kf`, which the tick kernels update in place too.
    """

    def __init__(self, params: WrenchKalmanParams):
        self.params = params
        self.dt = params.dt
        self.kf = np.zeros((5, len(params.K)))  # teleop.core.kernels.kalman's filter array: w, w_dot, K0, K1, meta
        self.kf[KK.K0] = [k[0] for k in params.K]
        self.kf[KK.K1] = [k[1] for k in params.K]
        self.kf[KK.META, 1] = params.dt
        self.reset()

    def reset(self) -> None:
        self.kf[KK.W] = 0.0
        self.kf[KK.W_DOT] = 0.0
        self.kf[KK.META, 0] = 0.0

    @property
    def started(self) -> bool:
        return bool(self.kf[KK.META, 0])

    @property
    def w(self) -> list:
        """Filtered wrench (6 floats)."""
        return self.kf[KK.W].tolist()

    @property
    def w_dot(self) -> list:
        """Its rate (6 floats) [N/s, N m/s]."""
        return self.kf[KK.W_DOT].tolist()

    def update(self, z) -> list:
        """Filtered wrench (list of 6 floats) from the measured wrench z (6 floats): teleop.core.kernels.kalman."""
        z = np.array(z, dtype=float)
        kalman_update(self.kf, z)
        return z.tolist()


class FilterpyWrenchKalman:
    """The same filter through filterpy's KalmanFilter predict/update (12 states, covariance kept)."""

    def __init__(self, params: WrenchKalmanParams, steady: bool = True):
        self.params = params
        self.steady = steady
        self.reset()

    def reset(self) -> None:
        self.kf = make_filterpy(self.params, self.steady)
        self.started = False

    def update(self, z) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        if not self.started:
            self.kf.x = np.zeros((12, 1))
            self.kf.x[0::2, 0] = z
            self.started = True
            return z.copy()
        self.kf.predict()
        self.kf.update(z)
        return self.kf.x[0::2, 0].copy()
