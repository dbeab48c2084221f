"""Compiled kernels: the one definition of each formula on the tick path, written once as plain scalar code
(numba `njit(cache=True)`; the same source runs as Python without numba, see `jit.py`).

Where each formula lives (the numpy array forms, the physics Steps, the estimators, the simulated robot and
the loop's tick all call these):
- geometry.py   ZYX rotation (eq 5), platform offsets, cable length and unit vector (eq 4), wrap angle
                (eq 6 + theta0), structure-matrix column (eq 8), inverse and forward kinematics
- friction.py   direction (Schmitt) rule, Dahl, Coulomb, viscous, Stribeck, the play (backlash) and its inverse
- effects.py    the effect catalogue's step kernels (one per effect, over the ones here) and the one driver
                that runs any of them over a whole signal
- sheath.py     the sheath: its parameters, friction state layout and capstan law (stick transitions, the start
                on the tip tension, the `dynamic` estimator's inverse, the seed's compensation eq 7)
- tension.py    the closed-form tension distribution of a one-dimensional null space
- kalman.py     the steady-state Kalman update
- estimate.py   the per-tick estimate of each estimator (one compiled call), turn correction, FSR branch
                lookup
- mapping.py    the stylus -> robot target -> cable length step (motion scale, workspace box, length clip,
                cable speed limit)
- sensor.py     the FSR reading chain (branch lag, conductance, the divider and its inverse, ADC), the FBG's
                eq 3 and the one-sensor model (seed 001 eq 7: its step, start and run)
- render.py     the force rendering: frame map, engage rule, ramp-in, passivity observer, norm clamp
- sim.py        the simulated robot's per-reading cable physics (pose terms, tension distribution, capstan)
- linalg.py     6 x 6 elimination (LU with complete pivoting, null vector, small solves) and Horner's rule
- ufuncs.py     element-wise loops over the scalar friction kernels (the physics array forms)
`jit.njit` is the one decorator (numba, cached on disk; the plain source without numba or with
TELEOP_NO_JIT=1). `warm.warm_up()` compiles (or loads from the on-disk cache) every kernel with the hot path's argument types;
the loop calls it before its first tick.
"""
