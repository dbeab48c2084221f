"""Campaigns: grids of simulated blind studies and fleets of recordings to diagnose, run on Dask.

A campaign file (TOML, `spec.py`, its values checked by `values.py`) names a study kind and what to run;
each kind (`blind.py`, `recordings.py`, `noop.py`) turns it into tasks. A task's identity (`identity.py`) is
everything its result depends on, hashed into its id, and its random streams derive from the campaign seed
and that identity, never from the order tasks run in. The scheduler (`scheduler.py`) runs tasks in-process (`none`), on a Dask
LocalCluster (`local:N`) or on a running Dask scheduler (`tcp://HOST:PORT`); the runner (`runner.py`)
writes each finished task atomically into the result store (`store.py`) as it completes, so a killed
campaign re-run skips what is done. `task_progress.py` shows how far it is; `plots.py` draws the results.
"""
