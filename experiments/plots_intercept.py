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

#: the forecast-miss axes are symmetric-log, linear within +-LINTHRESH_M
LINTHRESH_M = 10.0
#: what the forecast-miss axes' labels say of their scale (two more lines: the panels
#: are short, one line ran into the label of the panel above)
SYMLOG_NOTE = f"(symmetric log,\nlinear within ±{LINTHRESH_M:g} m)"
#: a panel's legend below it, over no data and within the panel's width (one column):
#: matplotlib's constrained layout makes room for it before the next panel
BELOW = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.03), "ncols": 1}


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
        # the interval's fill and its ends: one legend entry (the ends' line style says
        # the noise), so that the panel's legend fits below it in a column of two panels
        interval = f"{fs.words(estimator, noise)}: forecast-miss interval"
        for end in (lo, hi):
            ax[2].plot(t, end, **style, label=interval)
        ax[2].fill_between(t, lo, hi, color=style["color"], alpha=0.25, lw=0, label=interval)
        truth_pi = d["forecast_true_m"].to_numpy()
        ax[2].plot(t, truth_pi, color=fs.TRUTH, lw=1.0, label="truth's forecast miss")
        ax[2].set_yscale("symlog", linthresh=LINTHRESH_M)
        ax[2].set_ylabel(f"forecast miss Pi, m\n{SYMLOG_NOTE}")
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
        # The miss is a distance (the closest approach, unsigned), this axis the signed
        # forecast Pi: drawn at +miss, the ring of a run whose truth ends at -7002 m sat at
        # +6991 m, across zero. The ring marks where the truth's own forecast ends (its
        # last Pi in this channel: the curve it caps), the legend gives the miss. It is
        # drawn over the paper's stars (later, larger): both stay visible.
        ax[2].plot(
            [t[-1]], [truth_pi[-1]], "o", color=style["color"], ms=12, mfc="none", mew=1.8,
            zorder=5, label=f"ours: miss {miss:.1f} m (ring at the truth's final forecast)",
        )  # fmt: skip
        # (miss, fuel) or (miss, fuel, label): the label says whose numbers they are
        marks = tuple((paper or {}).get(noise, (None, None)))
        p_miss, p_fuel = marks[0], marks[1]
        who = str(marks[2]) if len(marks) > 2 else "paper"
        if p_miss is not None:
            # the paper prints a distance, no side: a star on either side of zero
            ax[2].plot([t[-1]] * 2, [-p_miss, p_miss], **fs.PAPER_MARKER,
                       label=f"{who}: miss {p_miss:g} m")  # fmt: skip
        if p_fuel is not None:
            fs.paper_line(ax[4], p_fuel, f"fuel {p_fuel:g} m/s", who=who)
        ax[0].set_title(
            f"{noise} errors: miss {miss:.1f} m, fuel {float(d['fuel_mps'].iloc[-1]):.1f} m/s"
        )
        for i, a in enumerate(ax):
            if i == 2:  # the interval fills its panel: the legend goes below it, in one column
                fs.legend(a, **BELOW)
            else:
                fs.legend(a, loc="best")
    fig.suptitle(
        f"{steps['scenario'].iloc[0]}: control processes, {fs.words(estimator)}, run {run}"
    )
    return fig


def estimator_overlay(
    steps: pd.DataFrame, run: int, noise: str, channel: str | None = None, axes=None
):
    """Forecast-miss intervals of every estimator in ``steps`` on one realisation; drawn
    on three given ``axes`` (then None is returned) or on a new figure.

    The steps where the truth's state is outside an estimator's belief are ticks in a
    strip of their own below the top panel, one row per such estimator (on the panel's
    data axis, about 0, they read as values of a few metres); the top panel's legend is
    below that strip, over no data."""
    fig = None
    if axes is None:
        fig, grid = fs.figure(3, 1, size=(7.0, 9.5), sharex="col")
        axes = grid[:, 0]
    ax = axes
    groups = list(steps[steps["noise"] == noise].groupby("estimator", sort=True))
    outside_rows: list[tuple[str, dict, np.ndarray]] = []
    for est, grp in groups:
        d = _one(grp, run, channel)
        t = d["t_s"].to_numpy()
        style = fs.line(str(est), noise)
        truth = d["forecast_true_m"].to_numpy()
        lo, hi = d["forecast_lo_m"].to_numpy() - truth, d["forecast_hi_m"].to_numpy() - truth
        # the fill and its ends: one entry (the noise is in the title; the ends' line
        # style shows it), so that the legend fits below the panel in two columns
        interval = f"{fs.words(est)}: interval - truth"
        for end in (lo, hi):
            ax[0].plot(t, end, **style, label=interval)
        ax[0].fill_between(t, lo, hi, color=style["color"], alpha=0.18, lw=0, label=interval)
        outside = ~d["truth_inside"].to_numpy(dtype=bool)
        if outside.any():
            outside_rows.append((str(est), style, t[outside]))
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
    ax[0].axhline(0.0, color=fs.TRUTH, lw=1.0, label="truth's forecast miss (0)")
    ax[0].set_yscale("symlog", linthresh=LINTHRESH_M)
    ax[0].set_ylabel(f"interval end - truth's Pi, m\n{SYMLOG_NOTE}")
    below = _outside_strip(ax[0], outside_rows)
    ax[1].set_yscale("log")
    ax[1].set_ylabel("interval width, m")
    ax[2].set_ylabel("fuel spent, m/s")
    ax[2].set_xlabel("time t, s")
    fs.legend(ax[0], loc="upper center", bbox_to_anchor=(0.5, below), ncols=2, fontsize=6.5)
    for a in ax[1:]:
        fs.legend(a, loc="best", fontsize=6.5)
    if fig is not None:
        fig.suptitle(
            f"{steps['scenario'].iloc[0]}: forecast-miss intervals on one realisation\n"
            f"(run {run}, {fs.NOISE_WORDS.get(noise, noise)}); the truth's forecast is inside "
            "where 0 lies between the ends"
        )
    return fig


def _outside_strip(ax, rows: list[tuple[str, dict, np.ndarray]]) -> float:
    """The steps where the truth's state is outside each estimator's belief, as ticks in
    a thin strip below ``ax`` (an inset sharing its time axis: no data axis to misread),
    one row per estimator of ``rows`` (name, line style, times). Returns where, in
    ``ax``'s axes fraction, what goes below it may start."""
    if not rows:
        return -0.03
    height = 0.07 * len(rows)
    strip = ax.inset_axes((0.0, -0.03 - height, 1.0, height), sharex=ax)
    for y, (est, style, times) in enumerate(rows):
        label = f"{fs.words(est)}: truth's state outside its belief (strip)"
        strip.plot(times, np.full(len(times), y), "|", color=style["color"], ms=7, label=label)
        ax.plot([], [], "|", color=style["color"], ms=7, label=label)  # its legend entry
    strip.set_ylim(-0.6, len(rows) - 0.4)
    strip.set_yticks(range(len(rows)), [fs.words(est) for est, _, _ in rows], fontsize=6.5)
    strip.set_ylabel("outside, -", fontsize=6.5)
    strip.tick_params(axis="x", labelbottom=False)
    strip.grid(False, axis="y")
    return -0.035 - height
