"""Force estimation (seed 000 §4): sensor tensions -> capstan compensation -> wrench f = -A t -> turn
compensation -> Kalman. Modules: `direction` (reversal detection), `turn` (step 3 fits), `kalman` (noise
model, filterpy and steady-state filters), `estimators` (the four named estimators), `tick` (the fast
per-tick computation for the loop and its plain reference)."""
