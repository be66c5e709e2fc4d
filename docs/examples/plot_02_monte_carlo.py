"""
A Monte Carlo study to a DataFrame
==================================

Eight runs of the Fig. 5 scenario (truth drawn from the a-priori box) with the
information set under random and game noise, in memory, and the CDFs of miss and fuel.
"""

import pandas as pd
from kalman_vs_infoset.experiments import plots

import kalman_vs_infoset as kvi

sc = kvi.load_scenario("kp_fig5")
frames = [kvi.run_experiment(sc, "infoset", noise, runs=8) for noise in ("random", "game")]
df = pd.concat(frames, ignore_index=True)
print(df.groupby("noise")[["miss_m", "fuel_mps"]].describe().T.round(2))

# %%
# Each row is one run (``docs/results.md`` lists the columns); the CDFs:
fig = plots.cdf_figure(df, ["estimator", "noise"], "kp_fig5: information set, 8 runs")
