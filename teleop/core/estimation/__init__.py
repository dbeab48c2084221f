"""Force estimation (seed 000 §4): sensor tensions -> capstan compensation -> wrench f = -A t -> turn
compensation -> Kalman.

Modules:
  direction   reversal detection with a dead band (cables, FSR branches, end-effector turns)
  estimators  the four named estimators (non_compensated, single, double, dynamic): update(t, L, pose, dt)
  turn        step 3: fit and apply the turn polynomials (frozen TurnCompensation)
  kalman      noise model, tuning, filterpy filter and its steady-state form
  calibrate   fitting `dynamic`'s friction parameters on the no-load run
  tick        TickComputer: one loop tick on plain floats (pose -> lengths, wrench, stylus force)
  reading     ReadingEstimator: raw robot readings -> (tensions, wrench) for the loop
"""
