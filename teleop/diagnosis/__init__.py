"""teleop/diagnosis: where simulation and a real recording differ, which physics is missing, and the fit.

    teleop diagnose REC... [--map mrdlab] --json F --plot F [--save-model M]
    teleop bench diagnose --cases 100 --seed 0 [--json F] [--speed]

Modules, in the order the data flows:

- recording_io: interchange CSV (docs/formats.md) and any layout through a TOML column map (maps/mrdlab.toml);
  malformed input -> one-line InputError naming file, line, column. session_export: MCAP sessions -> CSV.
- links: which links a recording holds (position motor -> tip, the spring law tip travel -> tip force,
  force tip load -> motor, contact indentation -> force) and the simulation of each: an affine map output =
  gain * input + offset (contact: gain * max(d, 0) + offset) with the baseline's effects (by default the
  project's simulation: capstan friction on force links; `diagnose(..., baseline=())` is lossless). Every
  catalogue effect is an addition to it, run from the shared physics registry (teleop.core.physics).
  docs/diagnosis.md tabulates which effect shows on which channel.
- locate: residual conditions (after motion reversals, speed, load, holds, loading/unloading,
  temperature, time, position period, indentation rate/depth) with R^2 evidence and time windows.
- identify: joint least-squares fits of baseline + effect (bounded parameters of the registry's specs),
  held-out ranking with parsimony and an information criterion, greedy additions; `none` when nothing
  pays. diagnose: the report (JSON keys: docs/formats.md), `unexplained` for structured residual left over.
- peer: a linear ARX model (numpy least squares), free-run scored on the same held-out split;
  sindy_peer: PySINDy (polynomial + Fourier library, STLSQ; static and free-run forms).
- crossfile: parameters identified on one recording scored on the others.
- model_io: save/load identified link models; `load_model(path)` gives physics Effects and Steps for
  the simulated robot and the estimator. feedforward: backlash pre-compensation of position commands.
- generator, scoring: concealed-effect recordings and the benchmark's confusion matrix.

Plots and reports made from MRDLab recordings carry: "Contains data from the MRDLab
mis-tool-characterization dataset, ODbL 1.0."
"""
