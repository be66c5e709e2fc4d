"""
Comparing estimators on the same realisations
=============================================

Run ``j`` draws the same truth and noise whatever the estimator, so the information set,
the EKF and the UKF are compared run by run (paired).
"""

import pandas as pd
from kalman_vs_infoset.experiments import plots

import kalman_vs_infoset as kvi

sc = kvi.load_scenario("kp_fig5")
df = pd.concat(
    [kvi.run_experiment(sc, est, "game", runs=6) for est in ("infoset", "ekf", "ukf")],
    ignore_index=True,
)
paired = df.pivot(index="run", columns="estimator", values="miss_m")
print(paired.round(2))
print("truth outside the belief (steps):", df.groupby("estimator")["truth_outside"].sum().to_dict())

# %%
fig = plots.cdf_figure(df, ["estimator", "noise"], "kp_fig5, game noise, 6 paired runs")
