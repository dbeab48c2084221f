"""Force estimation (seed 000 §4): sensor tensions -> capstan compensation -> wrench f = -A t -> turn
compensation -> Kalman.

Modules:
  direction   reversal detection with a dead band (cables, FSR branches, end-effector turns)
  estimators  the four estimators' names (non_compensated, single, double, dynamic) and `dynamic`'s
              friction parameters; each one's per-tick code is a kernel of teleop.core.kernels.estimate
  turn        step 3: fit and apply the turn polynomials (frozen TurnCompensation)
  kalman      noise model, tuning, filterpy filter and its steady-state form
  calibrate   fitting `dynamic`'s friction parameters on the no-load run
  tick        TickComputer (pose, tensions -> lengths, wrench, stylus force) and LoopTick (the loop's whole
              device-excluded tick, what `teleop bench tick` times)
  reading     ReadingEstimator: raw FSR readings -> (tensions, wrench) for the loop
  sensor_reading  the FBG and one-sensor kinds' estimators, make_estimator(geom, kind, name)
"""
