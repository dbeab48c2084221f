"""Across files: does what was identified on one recording hold on another?

For every ordered pair (A, B) of diagnosed recordings and every link of A with identified effects, the
effects keep A's parameters while B's baseline gain and offset are refitted on B's fit part; the model is
scored on B's held-out part against B's baseline. An effect that is physics (the same instrument under
another speed or load) keeps paying; one that fitted A's noise does not.
"""

from __future__ import annotations

import math

import numpy as np

from teleop.diagnosis.diagnose import Diagnosis, split
from teleop.diagnosis.identify import fit_chain
from teleop.core.physics.links import LinkModel


def cross_file(diags: list[Diagnosis]) -> dict:
    """{"pairs": [{"channel", "effects", "fitted_on", "scored_on", "rmse_before", "rmse_after",
    "improvement"}], "summary": {channel: {"chains", "pairs", "improvement_geomean", "improvement_min",
    "by_chain": {chain: min improvement}}}}."""
    pairs = []
    for A in diags:
        for resA in A.links:
            effects = resA.final.model.effects
            if not effects:
                continue
            for B in diags:
                if B is A:
                    continue
                resB = [r for r in B.links if r.data.link == resA.data.link]
                if not resB:
                    continue
                resB = resB[0]
                base = resB.baseline.model
                start = LinkModel(base.link, base.gain, base.offset, base.direction, base.load_sign, effects)
                fit_idx, hold_idx = split(B.rec.n, B.holdout)
                f = fit_chain(resB.data, start, (), fit_idx, hold_idx, freeze=True)
                pairs.append({"channel": resA.data.link.output, "effects": [n for n, _ in effects],
                              "fitted_on": A.rec.path, "scored_on": B.rec.path,
                              "rmse_before": resB.baseline.rmse_hold, "rmse_after": f.rmse_hold,
                              "improvement": resB.baseline.rmse_hold / max(f.rmse_hold, 1e-300)})
    summary = {}
    for ch in sorted({p["channel"] for p in pairs}):
        imps = [p["improvement"] for p in pairs if p["channel"] == ch]
        chains = sorted({"+".join(p["effects"]) for p in pairs if p["channel"] == ch})
        summary[ch] = {"chains": chains, "pairs": len(imps),
                       "improvement_geomean": math.exp(float(np.mean(np.log(imps)))),
                       "improvement_min": min(imps),
                       "by_chain": {c: min(p["improvement"] for p in pairs
                                           if p["channel"] == ch and "+".join(p["effects"]) == c)
                                    for c in chains}}
    return {"pairs": pairs, "summary": summary}
