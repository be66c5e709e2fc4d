"""
One engagement and its trace
============================

Run 0 of the paper's Fig. 3 engagement with the information set, as ``kvi intercept
kp_fig3`` computes it (the same seed, the same numbers), then its step-by-step history:
the set's interval of the forecast miss closing on the true forecast.
"""

import matplotlib.pyplot as plt

import kalman_vs_infoset as kvi

sc = kvi.load_scenario("kp_fig3")
result = kvi.run_engagement(sc, "infoset", "random", run=0)
print(f"miss {result.miss_m:.2f} m, fuel {result.fuel_mps:.1f} m/s")
print(
    f"paper (Fig. 3, random noise): {sc.reference.miss_random_m} m, "
    f"{sc.reference.fuel_random_mps} m/s"
)

# %%
# The row ``kvi intercept kp_fig3`` writes for run 0 is ``result.as_row()``, digit for digit.
steps, sets = kvi.trace(sc, "infoset", "random", runs=[0])
lat = steps[steps["channel"] == "lateral"]
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.fill_between(
    lat["t_s"],
    lat["forecast_lo_m"],
    lat["forecast_hi_m"],
    alpha=0.3,
    label="information set: forecast-miss interval",
)
ax.plot(lat["t_s"], lat["forecast_true_m"], "k", lw=1, label="true forecast miss")
ax.set_yscale("symlog", linthresh=10)
ax.set_xlabel("time, s")
ax.set_ylabel("forecast miss, m")
ax.legend(loc="upper right", fontsize=8)
fig.tight_layout()
