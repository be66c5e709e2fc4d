"""
An attitude loop with an estimator
==================================

The reaction-wheel satellite of Akimov's Fig. 3 (quaternion PD law), its attitude known
through the guaranteed box estimator from bounded measurements under random noise, beside
the same runs with an unscented Kalman filter. ``run_attitude`` runs the ``attitude``
command's loop in this process and returns its rows (no files); the command line's
``kvi attitude smallsat_rw --noise random --estimators box,ukf --runs 2`` writes the same
rows to a results folder.
"""

import pandas as pd

import kalman_vs_infoset as kvi

df = pd.concat(
    [
        kvi.run_attitude("smallsat_rw", noise="random", estimator=name, runs=2)
        for name in ("box", "ukf")
    ],
    ignore_index=True,
)
print(df[["estimator", "run", "settle_time_s", "energy_N2m2s", "final_angle_deg", "truth_outside"]])
