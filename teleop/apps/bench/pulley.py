"""`teleop bench pulley [--seed S] [--json F] [--plot F]`: seed 002's cable-pulley transmission (tension and
displacement) along a laparoscopic instrument's pulley chain, computed with teleop.core.physics.pulley.

The chain is built from the pulleys' places (`chain_from_layout`: each wrap angle and span from where the
pulleys sit), so the model has every per-pulley quantity seed 002 names: radius R_i, wrap theta_i, span d_i,
friction mu_i, the cable's bending rigidity EI and axial stiffness EA.

- tension transmission: the tip tension over the motor force, T_tip / F_m, pulling (pulley by pulley
  K_i T + EI / R_i^2), and F_m / T_tip releasing, cumulatively along the chain, over a sweep of tip tensions; beside it
  the classical capstan law alone (EI = 0), which seed 002's abstract says the tendon-sheath studies use.
- displacement transmission: the motor moves a triangle of STROKE_M under a constant tip tension; the tip
  follows x - elongation (`pulley_elongation`), the motor force travelling its band with the cable's stiffness
  EA / L at reversals (`pulley_motor_force`). Reported: the lost motion b at a reversal (the backlash) and
  the ratio of tip stroke to motor stroke.
- parameter spread (--seed): the friction and bending rigidity are not known from the paper, so each is drawn
  SPREAD_N times over a range (mu x U(0.5, 1.5), EI x U(0.5, 2)) and the 5-95 % range of both transmissions
  is reported.

What the paper gives: the project's copy of seed 002 holds its abstract, introduction and nomenclature only
(docs/papers.md); its parameter table, figures and measured transmissions are not available, so no number of
the paper is printed beside these, and every instrument parameter below is the project's own, its source named
in PARAMS (each row: value, unit, source).
"""

from __future__ import annotations

import math

import numpy as np

from scenes.pulley_transmission import INSTRUMENT_LAYOUT, PulleyTransmissionParams
from teleop.apps.argtypes import output_figure, output_file, seed_int
from teleop.core.physics.pulley import PulleyChain, chain_from_layout, pulley_band, pulley_elongation, \
    pulley_motor_force, segment_tensions
from teleop.io.figures import legend_outside
from teleop.io.outputs import save_figure, write_json

NOT_IN_PAPER = "not in the project's copy of seed 002 (abstract, introduction, nomenclature only)"

# the instrument: value, unit, source
_D = PulleyTransmissionParams()  # the instrument's one home (scenes.pulley_transmission), the robot's pulley plant's
PARAMS = {
    "mu": (_D.mu, "1", "project assumption: steel cable on steel pulleys, shaft friction folded in "
                      "(seed 002 nomenclature mu_c, mu_s; values " + NOT_IN_PAPER + ")"),
    "EI": (_D.EI, "N m^2", "project estimate: 7x19 steel cable 0.45 mm, wires bending independently "
                            "(133 x E pi d_w^4 / 64, d_w = 0.03 mm, E = 200 GPa); seed 002 names EI, value "
                            + NOT_IN_PAPER),
    "EA": (_D.EA, "N", "project estimate: same cable, metallic area 0.095 mm^2 x 100 GPa effective modulus "
                       "(seed 002 nomenclature E, A)"),
    "T_tip": (10.0, "N", "project assumption: grasping-load cable tension (seed 002 T_out)"),
}
# pulley places from the tip anchor to the motor exit (scenes.pulley_transmission.INSTRUMENT_LAYOUT)
LAYOUT = INSTRUMENT_LAYOUT
LAYOUT_SOURCE = "project layout (seed 002 locates its pulleys in a figure " + NOT_IN_PAPER + ")"
STROKE_M = 0.005
SPREAD_N = 200
T_SWEEP = np.linspace(0.5, 20.0, 40)


def register(subparsers) -> None:
    p = subparsers.add_parser("pulley", help="seed 002's cable-pulley tension and displacement transmission "
                                             "along an instrument's pulley chain")
    p.add_argument("--seed", type=seed_int, default=0, help="seed of the parameter spread's draws (default 0)")
    p.add_argument("--json", type=output_file, metavar="F", help="write the numbers as JSON")
    p.add_argument("--plot", type=output_figure, metavar="F", help="write the figure (PNG)")
    p.set_defaults(func=run)


def instrument(mu: float | None = None, EI: float | None = None) -> PulleyChain:
    """The bench's chain (LAYOUT, PARAMS), mu [-] and EI [N m^2] replaceable."""
    return chain_from_layout(LAYOUT, PARAMS["mu"][0] if mu is None else mu,
                             EI=PARAMS["EI"][0] if EI is None else EI, EA=PARAMS["EA"][0])


def tension_transmission(chain: PulleyChain, T_tip) -> dict:
    """Output over input tension [-] in the driving direction for tip tensions T_tip (n,) [N] (> 0):
    'pulling' T_tip / F_m (the motor drives) and 'releasing' F_m / T_tip (the load drives), (n,); and
    'cumulative' (p,): T_tip / T after each pulley, pulling, at T_tip[0]. Both are 1 for a lossless chain."""
    T = np.atleast_1d(np.asarray(T_tip, dtype=float))
    lo, hi = pulley_band(T, chain)
    seg = segment_tensions(T[:1], chain, True)[:, 0]
    return {"pulling": T / hi, "releasing": lo / T, "cumulative": seg[0] / seg[1:]}


def displacement_transmission(chain: PulleyChain, T_tip: float, stroke: float = STROKE_M, n: int = 801) -> dict:
    """Motor triangle 0 -> stroke -> 0 -> stroke [m] (n points per leg) under tip tension T_tip [N]; stick
    stiffness EA / L (the cable's, L the chain's length). Returns x, tip, F_m (arrays), the lost motion b [m]
    (elongation pulling minus releasing) and ratio = tip stroke / motor stroke over the last leg."""
    leg = np.linspace(0.0, stroke, n)
    x = np.concatenate([leg, leg[::-1][1:], leg[1:]])
    L = float(np.sum(chain.spans))
    k = chain.EA / L if math.isfinite(chain.EA) else 1e12
    T = np.full(x.shape, float(T_tip))
    lo, hi = pulley_band(T[:1], chain)
    F = pulley_motor_force(x, T, chain, k, F0=float(lo[0]))
    tip = x - pulley_elongation(F, T, chain)
    b = float(pulley_elongation(hi, T[:1], chain)[0] - pulley_elongation(lo, T[:1], chain)[0])
    last = slice(2 * (n - 1), None)
    return {"x": x, "tip": tip, "F_m": F, "lost_motion_m": b,
            "ratio": float(np.ptp(tip[last]) / np.ptp(x[last]))}


def spread(seed: int, T_tip: float) -> dict:
    """5-95 % ranges of the pulling tension ratio and the lost motion [m] over SPREAD_N draws of mu and EI."""
    rng = np.random.default_rng(seed)
    mus = PARAMS["mu"][0] * rng.uniform(0.5, 1.5, SPREAD_N)
    EIs = PARAMS["EI"][0] * rng.uniform(0.5, 2.0, SPREAD_N)
    ratio, b = [], []
    for mu, EI in zip(mus, EIs):
        ch = instrument(mu, EI)
        ratio.append(tension_transmission(ch, [T_tip])["pulling"][0])
        lo, hi = pulley_band([T_tip], ch)
        b.append(float(pulley_elongation(hi, [T_tip], ch)[0] - pulley_elongation(lo, [T_tip], ch)[0]))
    return {"tension_ratio_5_95": np.percentile(ratio, [5, 95]).tolist(),
            "lost_motion_m_5_95": np.percentile(b, [5, 95]).tolist()}


def compute(seed: int) -> dict:
    T0 = PARAMS["T_tip"][0]
    models = {"bending": instrument(), "capstan": instrument(EI=0.0)}
    out = {"params": {k: {"value": v, "unit": u, "source": s} for k, (v, u, s) in PARAMS.items()},
           "layout": {"rows_x_y_rho_m": [list(r) for r in LAYOUT], "source": LAYOUT_SOURCE},
           "pulleys": [{"theta_deg": math.degrees(p.theta), "R_m": p.R, "mu": p.mu, "span_m": p.d}
                       for p in models["bending"].pulleys],
           "d_tip_m": models["bending"].d_tip, "T_sweep_N": T_SWEEP, "paper": NOT_IN_PAPER, "models": {}}
    for name, ch in models.items():
        tt = tension_transmission(ch, np.concatenate([[T0], T_SWEEP]))
        dt = displacement_transmission(ch, T0)
        out["models"][name] = {"tension_ratio_pulling": float(tt["pulling"][0]),
                               "tension_ratio_releasing": float(tt["releasing"][0]),
                               "cumulative_pulling": tt["cumulative"],
                               "sweep_pulling": tt["pulling"][1:], "sweep_releasing": tt["releasing"][1:],
                               "lost_motion_m": dt["lost_motion_m"], "displacement_ratio": dt["ratio"],
                               "loop": {k: dt[k] for k in ("x", "tip", "F_m")}}
    out["spread"] = {"seed": seed, "draws": SPREAD_N, **spread(seed, T0)}
    return out


def table(res: dict) -> str:
    T0 = PARAMS["T_tip"][0]
    lines = ["seed 002 cable-pulley transmission (paper's values: " + res["paper"] + ")",
             "pulley  theta [deg]  R [mm]  span to next [mm]  T_tip/T after it (pulling, with EI)"]
    for i, (p, c) in enumerate(zip(res["pulleys"], res["models"]["bending"]["cumulative_pulling"]), 1):
        lines.append(f"{i:>6}  {p['theta_deg']:>11.1f}  {p['R_m'] * 1e3:>6.2f}  {p['span_m'] * 1e3:>17.1f}  {c:.3f}")
    lines.append(f"at T_tip = {T0:g} N, stroke {STROKE_M * 1e3:g} mm:      with bending EI   capstan only (EI=0)")
    b, c = res["models"]["bending"], res["models"]["capstan"]
    rows = (("tension ratio T_tip/F_m pulling", "tension_ratio_pulling", 1.0, ".3f"),
            ("tension ratio F_m/T_tip releasing", "tension_ratio_releasing", 1.0, ".3f"),
            ("lost motion at reversal [mm]", "lost_motion_m", 1e3, ".4f"),
            ("displacement ratio tip/motor stroke", "displacement_ratio", 1.0, ".4f"))
    for label, key, scale, fmt in rows:
        lines.append(f"  {label:<36} {b[key] * scale:>12{fmt}}   {c[key] * scale:>10{fmt}}")
    s = res["spread"]
    lines.append(f"spread over {s['draws']} draws (mu x U(0.5,1.5), EI x U(0.5,2), seed {s['seed']}): tension ratio "
                 f"{s['tension_ratio_5_95'][0]:.3f}-{s['tension_ratio_5_95'][1]:.3f}, lost motion "
                 f"{s['lost_motion_m_5_95'][0] * 1e3:.4f}-{s['lost_motion_m_5_95'][1] * 1e3:.4f} mm (5-95 %)")
    return "\n".join(lines)


def figure(res: dict):
    import matplotlib  # heavy: loaded only to draw
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # heavy: loaded only to draw

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.6))
    for name, (s_pull, s_rel) in (("bending", ("-", "-")), ("capstan", ((0, (6, 4)), (3, (6, 4))))):
        m = res["models"][name]
        label = "with bending rigidity" if name == "bending" else "capstan only (EI = 0)"
        a1.plot(res["T_sweep_N"], m["sweep_pulling"], color="C0", ls=s_pull,
                label=f"pulling (T_tip / F_motor), {label}")
        a1.plot(res["T_sweep_N"], m["sweep_releasing"], color="C1", ls=s_rel,
                label=f"releasing (F_motor / T_tip), {label}")
        a2.plot(m["loop"]["x"] * 1e3, m["loop"]["tip"] * 1e3, color="C2" if name == "bending" else "C3",
                ls="-" if name == "bending" else "--", label=label)
    a1.axhline(1.0, color="0.6", lw=0.8, label="lossless")
    a1.set_xlabel("tip tension T_tip [N]")
    a1.set_ylabel("tension ratio output / input [-]")
    a1.set_title("tension transmission")
    legend_outside(a1, "below")
    x = res["models"]["bending"]["loop"]["x"] * 1e3
    a2.plot([x.min(), x.max()], [x.min(), x.max()], color="0.6", lw=0.8, label="rigid cable (tip = motor)")
    a2.set_xlabel("motor displacement [mm]")
    a2.set_ylabel("tip displacement [mm]")
    a2.set_title(f"displacement transmission at T_tip = {PARAMS['T_tip'][0]:g} N")
    legend_outside(a2, "below")
    fig.suptitle("seed 002 cable-pulley model, project instrument (3 pulleys, 0.45 mm steel cable); "
                 "paper's curves not available")
    fig.tight_layout()
    return fig


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items() if k != "loop"}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def run(args) -> int:
    res = compute(args.seed)
    print(table(res))
    if args.json:
        write_json(args.json, _jsonable(res))
    if args.plot:
        save_figure(figure(res), args.plot)
    return 0
