"""
An attitude loop with an estimator
==================================

The reaction-wheel satellite of Akimov's Fig. 3 (quaternion PD law), its attitude known
through the guaranteed box estimator from bounded measurements under random noise. The
command line's ``attitude`` command runs it; its results table is read back in one call.
"""

import tempfile

from kalman_vs_infoset.experiments.cli import main

import kalman_vs_infoset as kvi

out = tempfile.mkdtemp()
main(
    [
        "attitude",
        "smallsat_rw",
        "--noise",
        "random",
        "--estimators",
        "box,perfect",
        "--runs",
        "2",
        "--out",
        out,
        "--no-progress",
    ]
)
df = kvi.load_results(out)
print(df[["estimator", "run", "settle_time_s", "energy_N2m2s", "final_angle_deg", "truth_outside"]])
