"""Figures of intercept traces (:mod:`experiments.traces`): control processes and overlays.

* :func:`control_processes`: the seed's Fig. 3 layout, one column per noise (random |
  game side by side) for one estimator and run: the bearing and its measurement, the
  bearing error within its bound, the forecast-miss interval the guidance uses against
  the truth's forecast, the impulses and the fuel spent, with the paper's printed
  miss and fuel marked when given;
* :func:`estimator_overlay`: the forecast-miss intervals of several estimators on the
  same realisation (same initial truth and noise stream), each against its own truth
  (the loops are closed, so the truths part as the impulses differ): the interval
  relative to the truth's forecast, its width, and the fuel spent.

Style (colour = estimator, line style = noise): :mod:`kalman_vs_infoset.experiments.figstyle`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import figstyle as fs


def _one(df: pd.DataFrame, run: int, channel: str | None) -> pd.DataFrame:
    d = df[df["run"] == run]
    if channel is None:
        channel = str(d["channel"].iloc[0])
    return d[d["channel"] == channel].sort_values("step")


def control_processes(
    steps: pd.DataFrame,
    run: int,
    estimator: str,
    noises: list[str],
    channel: str | None = None,
    paper: Mapping[str, tuple[Any, ...]] | None = None,
):
    """Fig. 3-style panels; ``paper`` maps a noise to its printed ``(miss_m, fuel_mps)``
    or ``(miss_m, fuel_mps, label)``, the label naming whose numbers they are (default
    "paper"; e.g. "paper Fig. 3, one run" on the Fig. 5 scenarios)."""
    fig, axes = fs.figure(5, len(noises), size=(5.2 * len(noises), 10.5), sharex="col")
    for col, noise in enumerate(noises):
        d = _one(steps[(steps["estimator"] == estimator) & (steps["noise"] == noise)], run, channel)
        ax = axes[:, col]
        style = fs.line(estimator, noise)
        t = d["t_s"].to_numpy()
        ax[0].plot(t, d["alpha_true_rad"] * 1e3, color=fs.TRUTH, lw=1.0, label="truth")
        ax[0].plot(t, d["alpha_meas_rad"] * 1e3, ".", color=fs.MEASURED, ms=2, label="measured")
        ax[0].set_ylabel("bearing alpha, mrad")
        ax[1].plot(
            t, d["alpha_err_rad"] * 1e6, ".", color=fs.MEASURED, ms=2, label="measurement error"
        )
        for sign in (-1, 1):
            ax[1].plot(
                t,
                sign * d["alpha_bound_rad"] * 1e6,
                color=fs.REFERENCE,
                lw=0.8,
                label="error bound",
            )
        ax[1].set_ylabel("bearing error, µrad")
        lo, hi = d["forecast_lo_m"].to_numpy(), d["forecast_hi_m"].to_numpy()
        ax[2].fill_between(
            t,
            lo,
            hi,
            color=style["color"],
            alpha=0.25,
            lw=0,
            label=f"{fs.words(estimator)}: forecast-miss interval",
        )
        for end in (lo, hi):
            ax[2].plot(t, end, **style, label=f"{fs.words(estimator, noise)}: interval ends")
        ax[2].plot(t, d["forecast_true_m"], color=fs.TRUTH, lw=1.0, label="truth's forecast miss")
        ax[2].set_yscale("symlog", linthresh=10.0)
        ax[2].set_ylabel("forecast miss Pi, m")
        k = d["impulse_mps"].to_numpy()
        fired = k != 0
        ax[3].vlines(
            t[fired],
            0,
            k[fired],
            color=style["color"],
            lw=1.0,
            label=f"{fs.words(estimator, noise)}: impulses",
        )
        ax[3].set_ylabel("impulse, m/s")
        ax[4].plot(t, d["fuel_mps"], **style, label=f"{fs.words(estimator, noise)}: fuel so far")
        ax[4].set_ylabel("fuel spent, m/s")
        ax[4].set_xlabel("time t, s")
        miss = float(d["miss_m"].iloc[0]) if "miss_m" in d else float("nan")
        # a ring over the paper's star (drawn later, larger): both stay visible
        ax[2].plot(
            [t[-1]], [miss], "o", color=style["color"], ms=12, mfc="none", mew=1.8, zorder=5,
            label=f"ours: miss {miss:.1f} m",
        )  # fmt: skip
        # (miss, fuel) or (miss, fuel, label): the label says whose numbers they are
        marks = tuple((paper or {}).get(noise, (None, None)))
        p_miss, p_fuel = marks[0], marks[1]
        who = str(marks[2]) if len(marks) > 2 else "paper"
        if p_miss is not None:
            ax[2].plot([t[-1]], [p_miss], **fs.PAPER_MARKER, label=f"{who}: miss {p_miss:g} m")
        if p_fuel is not None:
            fs.paper_line(ax[4], p_fuel, f"fuel {p_fuel:g} m/s", who=who)
        ax[0].set_title(
            f"{noise} errors: miss {miss:.1f} m, fuel {float(d['fuel_mps'].iloc[-1]):.1f} m/s"
        )
        # the forecast-miss interval fills its panel: its legend goes in a band of four
        # decades above the data (symlog), where "best" had put it over the interval
        y_lo, y_hi = ax[2].get_ylim()
        ticks = [v for v in ax[2].get_yticks() if y_lo <= v <= y_hi]  # none in the band
        ax[2].set_ylim(y_lo, max(y_hi, 10.0) * 1e4)
        ax[2].set_yticks(ticks)
        for i, a in enumerate(ax):
            fs.legend(a, **({"loc": "upper center", "ncols": 2} if i == 2 else {"loc": "best"}))
    fig.suptitle(
        f"{steps['scenario'].iloc[0]}: control processes, {fs.words(estimator)}, run {run}"
    )
    return fig


def estimator_overlay(
    steps: pd.DataFrame, run: int, noise: str, channel: str | None = None, axes=None
):
    """Forecast-miss intervals of every estimator in ``steps`` on one realisation; drawn
    on three given ``axes`` (then None is returned) or on a new figure."""
    fig = None
    if axes is None:
        fig, grid = fs.figure(3, 1, size=(7.0, 8.5), sharex="col")
        axes = grid[:, 0]
    ax = axes
    groups = list(steps[steps["noise"] == noise].groupby("estimator", sort=True))
    for k, (est, grp) in enumerate(groups):
        d = _one(grp, run, channel)
        t = d["t_s"].to_numpy()
        style = fs.line(str(est), noise)
        truth = d["forecast_true_m"].to_numpy()
        lo, hi = d["forecast_lo_m"].to_numpy() - truth, d["forecast_hi_m"].to_numpy() - truth
        ax[0].fill_between(
            t,
            lo,
            hi,
            color=style["color"],
            alpha=0.18,
            lw=0,
            label=f"{fs.words(est, noise)}: interval - truth",
        )
        for end in (lo, hi):
            ax[0].plot(t, end, **style, label=f"{fs.words(est, noise)}: interval ends - truth")
        outside = ~d["truth_inside"].to_numpy(dtype=bool)
        if outside.any():
            # one row of ticks per estimator about 0 (in the axis's linear part): on one
            # row the last estimator's ticks hid the others'
            row = (k - (len(groups) - 1) / 2.0) * 4.0
            ax[0].plot(
                t[outside],
                np.full(outside.sum(), row),
                "|",
                color=style["color"],
                ms=8,
                label=f"{fs.words(est)}: truth's state outside its belief",
            )
        ax[1].plot(
            t,
            d["forecast_hi_m"] - d["forecast_lo_m"],
            **style,
            label=f"{fs.words(est, noise)}: interval width",
        )
        miss = float(d["miss_m"].iloc[0])
        ax[2].plot(
            t, d["fuel_mps"], **style, label=f"{fs.words(est, noise)}: fuel, miss {miss:.1f} m"
        )
    ax[0].axhline(0.0, color=fs.TRUTH, lw=1.0, label="truth's forecast miss")
    ax[0].set_yscale("symlog", linthresh=10.0)
    ax[0].set_ylabel("interval end - truth's Pi, m")
    ax[1].set_yscale("log")
    ax[1].set_ylabel("interval width, m")
    ax[2].set_ylabel("fuel spent, m/s")
    ax[2].set_xlabel("time t, s")
    for a in ax:
        fs.legend(a, loc="best", fontsize=6.5)
    if fig is not None:
        fig.suptitle(
            f"{steps['scenario'].iloc[0]}: forecast-miss intervals on one realisation\n"
            f"(run {run}, {noise} errors); the truth's forecast is inside where 0 lies "
            "between the ends"
        )
    return fig
