"""teleop/core/physics: transmission, sensor and contact effects, one small model each (docs/architecture.md).

Every effect is registered under its canonical name and used three ways:

    from teleop.core.physics import Signals, chain, fit, get_effect
    eff = get_effect("backlash")
    sig = Signals(t=t, x=motor_pos)                      # SI arrays (n,); v derived from x
    tip = eff.apply(sig, {"width": 1e-3})                # (a) whole signal -> output channel (n,)
    st = eff.make_step({"width": 1e-3})                  # (b) real time: st.step(x=x_k) per sample,
    tip_k = st.step(x=0.002)                             #     the same kernel, state kept in st; st.reset();
    tips = st.run(x=motor_pos)                           #     st.run: a batch from st's state
    res = fit(eff, sig, measured_tip)                    # (c) identify: res.params, res.stderr, res.rmse
    res = fit("capstan_friction", Signals(t=t, x=x, load=F_tip), F_motor,
              fixed={"theta": 2.44}, mask=train)        # fixed parameters, residual on `train` only
    pad = chain("hertz_contact", "viscoelasticity", "contact_damping")   # one effect, params "hertz_contact.k", ...

Each effect registers with its own rules (`Rules`: the channel it shows on, primary parameters, what it
cannot be told apart from, fit starts, held parameters, a wrong-form test, a generator draw), which the
diagnosis, the generators and the docs read: a new effect is one module that registers it (imported below)
plus its test scenario. `catalogue.catalogue_rows()` lists the registry.

Conventions: x increasing = the motor hauls its cable in (pulling phase); force-link effects turn the
tip load into the motor-side force (their `output` is "load": the load seen by the next element towards
the motor); sensor effects turn the true force into the reading; contact effects give the pad force,
zero out of contact (d <= 0) and never negative.

Inputs are `Signals` channels (t, x, v, load, force, temperature, theta, d, d_dot; see base.CHANNELS).
`Effect.inputs` names the channels an effect needs (`Effect.optional` those it uses when present), and
the same names are the keywords of its `Step.step`. `Effect.output` is the channel its result stands
for; `chain(...)` feeds one effect's output to the next. Parameters are {name: float} dicts in SI units;
`Effect.params` holds their `ParamSpec` (unit, fit bounds, default, meaning).

The catalogue is the registry: `catalogue.catalogue_rows()` lists each effect's link, inputs -> output,
parameters and rules (docs/diagnosis.md's catalogue table is generated from it). Every module of this
package is imported here, the named ones first (their order is the registry's), then any other, so a new
effect's module registers it without an edit here.

Each effect's physics is written once, as a compiled step kernel `step(state, input, params) -> output`
(teleop.core.kernels.effects; `Kernel` on the Effect): the array form is the one compiled driver's loop over
it (kernels.effects.drive), the Step calls it per sample. The module-level functions (tip2motor_transitions,
backlash, cable_stretch, dahl, hysteresis_offset, thermal_offset, linear_force, hertz_force, sls_force,
damped_force, spring_force, pulley_motor_force, transport_delay, first_order_lag) run the same kernels; coulomb, viscous, stribeck and the
capstan's hold law are element-wise loops over the scalar kernels those steps call.
"""

import importlib
import pkgutil

from teleop.core.physics.base import (CHANNELS, REGISTRY, Effect, LinkRecord, ParamSpec, Rules, Scale, Signals,
                                      Step, alike, chain, get_effect, register, unregister)
from teleop.core.physics.capstan import (CapstanCompensator, capstan_band, capstan_in, capstan_out, motor2tip,
                                    motor2tip_transitions, tip2motor, tip2motor_transitions)
from teleop.core.physics.backlash import backlash
from teleop.core.physics.compliance import cable_stretch
from teleop.core.physics.spring import spring_force
from teleop.core.physics.pulley import Pulley, PulleyChain, pulley_band, pulley_elongation, pulley_motor_force
from teleop.core.physics.friction import coulomb, dahl, stribeck, viscous
from teleop.core.physics.sensor_effects import hysteresis_offset, thermal_offset
from teleop.core.physics.contact import damped_force, hertz_force, linear_force, sls_force
from teleop.core.physics.lag import first_order_lag, transport_delay
from teleop.core.physics.fit import FitResult, fit, rmse

for _module in pkgutil.iter_modules(__path__):   # a new effect's module registers it (see above)
    importlib.import_module(f"{__name__}.{_module.name}")

__all__ = [
    "CHANNELS", "REGISTRY", "Effect", "LinkRecord", "ParamSpec", "Rules", "Scale", "Signals", "Step", "alike",
    "chain", "get_effect", "register", "unregister",
    "CapstanCompensator", "capstan_band", "capstan_in", "capstan_out", "motor2tip", "motor2tip_transitions",
    "tip2motor", "tip2motor_transitions", "backlash", "cable_stretch", "spring_force", "coulomb", "dahl", "stribeck",
    "viscous", "hysteresis_offset", "thermal_offset", "damped_force", "hertz_force", "linear_force",
    "sls_force", "FitResult", "fit", "rmse", "Pulley", "PulleyChain", "pulley_band", "pulley_elongation",
    "pulley_motor_force", "transport_delay", "first_order_lag",
]
