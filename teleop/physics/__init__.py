"""teleop/physics: transmission, sensor and contact effects, one small model each (DESIGN.md catalogue).

Every effect is registered under its canonical name and used three ways:

    from teleop.physics import Signals, get_effect, fit
    eff = get_effect("backlash")
    sig = Signals(t=t, x=motor_pos)                      # SI arrays (n,); v derived from x
    tip = eff.apply(sig, {"width": 1e-3})                # (a) whole signal -> output channel (n,)
    st = eff.make_step({"width": 1e-3})                  # (b) real time: st.step(x=...) per sample
    res = fit(eff, sig, measured_tip)                    # (c) identify: res.params, res.stderr, res.rmse

Inputs are `Signals` channels (t, x, v, load, force, temperature, theta, d, d_dot; see base.CHANNELS);
`Effect.inputs` names the ones an effect needs, and the same names are the keywords of its `Step.step`.
The pure math lives in module-level functions (e.g. `capstan.tip2motor_transitions`, `backlash.backlash`);
stateful models are solved by vectorised prefix scans (`scan.py`), not Python loops.
"""

from teleop.physics.base import CHANNELS, REGISTRY, Effect, ParamSpec, Signals, Step, get_effect, register
from teleop.physics.capstan import (CapstanCompensator, capstan_band, capstan_in, capstan_out, motor2tip,
                                    motor2tip_transitions, tip2motor, tip2motor_transitions)
from teleop.physics.backlash import backlash
from teleop.physics.fit import FitResult, fit, rmse

__all__ = [
    "CHANNELS", "REGISTRY", "Effect", "ParamSpec", "Signals", "Step", "get_effect", "register",
    "CapstanCompensator", "capstan_band", "capstan_in", "capstan_out", "motor2tip", "motor2tip_transitions",
    "tip2motor", "tip2motor_transitions", "backlash", "FitResult", "fit", "rmse",
]
