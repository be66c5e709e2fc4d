"""Time histories of attitude traces (:mod:`kalman_vs_infoset.experiments.attitude_traces`).

:func:`time_histories` is the figure the ``attitude`` command draws for a traced run:
per body axis (columns) the attitude error, the body rate, the torque on the body and
the actuator momentum (with the limits where the loop has them), and below them the
principal error angle with the estimator's knowledge bound, the energy index so far
and, where the loop has them, the gyrostat's switching functions or the energy law's
auxiliary system. :func:`axis_panels` and :func:`step_panel` are the building blocks
of the paper figures (:mod:`kalman_vs_infoset.experiments.paper_figures`).

One curve per trace, coloured by its estimator and styled by its noise
(:mod:`experiments.figstyle`); limits and references are grey, the truth is what the
curves show (the loops' true state), the belief's centre is the thin curve.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import figstyle as fs

AXES = (1, 2, 3)
#: (column, axis label) of the per-axis rows, in order
ROWS = (
    ("error_deg", "attitude error, deg"),
    ("rate_degps", "body rate, deg/s"),
    ("torque_Nm", "torque on the body, N m"),
    ("momentum_Nms", "actuator momentum, N m s"),
)


def _label(df: pd.DataFrame, what: str = "") -> str:
    est, noise = str(df["estimator"].iloc[0]), str(df["noise"].iloc[0])
    run = int(df["run"].iloc[0]) if "run" in df else 0
    runs = f", run {run}" if run else ""
    return f"{fs.words(est, noise)}{runs}" + (f": {what}" if what else "")


def _style(df: pd.DataFrame) -> dict:
    return fs.line(str(df["estimator"].iloc[0]), str(df["noise"].iloc[0]))


def axis_panels(
    axes,
    traces: Sequence[pd.DataFrame],
    column: str,
    ylabel: str,
    what: str = "",
    limit: str | None = None,
    lw: float | None = None,
) -> None:
    """``column`` of each trace against time on three axis panels (``axes`` of 3); ``lw``
    (line width) tells apart variants of one estimator and noise."""
    for ax, k in zip(axes, AXES, strict=True):
        for df in traces:
            d = df[df["axis"] == k]
            style = {**_style(df), **({"lw": lw} if lw else {})}
            ax.plot(d["t_s"], d[column], **style, label=_label(df, what))
            if limit is not None and limit in d and np.isfinite(d[limit]).any():
                lim = d[limit].to_numpy(dtype=float)
                ax.plot(d["t_s"], lim, color=fs.REFERENCE, lw=0.8, ls="-", label="limit")
                ax.plot(d["t_s"], -lim, color=fs.REFERENCE, lw=0.8, ls="-", label="limit")
        ax.set_ylabel(
            f"{ylabel} ({'xyz'[k - 1]})"
            if ", " not in ylabel
            else ylabel.replace(",", f" ({'xyz'[k - 1]}),", 1)
        )
        ax.set_xlabel("time t, s")


def step_panel(ax, traces: Sequence[pd.DataFrame], column: str, ylabel: str, what: str = ""):
    """A per-step ``column`` of each trace against time."""
    for df in traces:
        d = df[df["axis"] == 1]
        ax.plot(d["t_s"], d[column], **_style(df), label=_label(df, what))
    ax.set_ylabel(ylabel)
    ax.set_xlabel("time t, s")


def _limits(df: pd.DataFrame, column: str) -> str | None:
    """The column of the limit of ``column`` in this loop, if it has one."""
    if column == "torque_Nm":
        return "torque_limit_Nm" if "torque_limit_Nm" in df else "torque_max_Nm"
    return "momentum_max_Nms" if column == "momentum_Nms" else None


def history_title(scenario: str, controller: str | None, runs: Sequence[int], seed=None,
                  who: str = "") -> str:  # fmt: skip
    """The time histories' title in words (``kvi attitude``'s and ``kvi plot``'s): the
    scenario, the controller, ``who`` (an estimator and noise) when one trace is drawn,
    the runs and the seed."""
    which = ", ".join(str(r) for r in runs) or "0"
    head = scenario + (f", {controller} controller" if controller else "")
    seed_text = "" if seed is None else f" (seed {seed})"
    return (f"{head}: time histories, {who + ', ' if who else ''}"
            f"run{'s' if len(runs) > 1 else ''} {which}{seed_text}")  # fmt: skip


def time_histories(traces: Sequence[pd.DataFrame], title: str = ""):
    """The attitude command's figure of one or more traced runs (module docstring)."""
    first = traces[0]
    extra = []
    if "psi" in first:
        extra = [("eta", "error quaternion eta_i, -"), ("psi", "switching function psi_i, -")]
    elif "xi_deg" in first and np.isfinite(first["xi_deg"]).any():
        extra = [("xi_deg", "auxiliary system xi (angle), deg")]
    rows = list(ROWS) + extra
    fig, axes = fs.figure(len(rows) + 1, 3, size=(13.0, 2.3 * (len(rows) + 1)), sharex=True)
    for r, (col, ylabel) in enumerate(rows):
        if col in first:
            axis_panels(axes[r], traces, col, ylabel, limit=_limits(first, col))
    bottom = axes[len(rows)]
    for df in traces:
        d = df[df["axis"] == 1]
        style = _style(df)
        # the same run's line on every panel: one legend entry (its panels say what)
        bottom[0].plot(d["t_s"], d["angle_deg"], **style, label=_label(df))
        kb = d["knowledge_bound_deg"].to_numpy(dtype=float)
        if np.nanmax(kb, initial=0.0) > 1e-9:  # a perfect, noiseless belief has none
            bottom[0].plot(
                d["t_s"],
                kb,
                color=style["color"],
                lw=0.8,
                ls=":",
                label=_label(df, "knowledge bound of the belief"),
            )
        bottom[1].plot(d["t_s"], d["energy_N2m2s"], **style, label=_label(df))
        bottom[2].plot(d["t_s"], d["rate_norm_degps"], **style, label=_label(df))
        if "guaranteed_time_s" in d:
            tau = float(d["guaranteed_time_s"].iloc[0])
            for ax in bottom:
                ax.axvline(tau, color=fs.REFERENCE, ls="--", lw=0.9, label="guaranteed time tau")
    panels = ((bottom[0], "angle_deg", "error angle, deg"),
              (bottom[2], "rate_norm_degps", "rate norm, deg/s"))  # fmt: skip
    for ax, col, what in panels:
        # the rows drawn (axis 1's)
        values = np.concatenate(
            [df.loc[df["axis"] == 1, col].to_numpy(dtype=float) for df in traces]
        )
        # log where there is something to draw on one (a run that diverged at once has
        # no positive finite value: matplotlib warned and drew an empty log axis)
        if np.any(np.isfinite(values) & (values > 0)):
            ax.set_yscale("log")
            # a zero (a turn from rest starts at rate 0) leaves the log axis unseen
            if np.any(values <= 0.0):
                what += "\n(log; zeros not drawn)"
        ax.set_ylabel(what)
    # two lines: one ran into the panel above (the energy index Z of the CDFs, M^T M)
    bottom[1].set_ylabel("energy so far\n(sum M^T M dt), N^2 m^2 s")
    for ax in bottom:
        ax.set_xlabel("time t, s")
    for ax in axes[: len(rows)].flat:  # the time axis is shared: labelled once, below
        ax.set_xlabel("")
    # one legend below the panels (the same curves on every panel): eighteen per-panel
    # legends repeated the entries, covered data and cost a third of the figure's time
    fs.figure_legend(fig, axes.flat, fontsize=7, ncol=3)
    fig.suptitle(title or f"{first['scenario'].iloc[0]}: time histories")
    return fig


def segment_points(df: pd.DataFrame, settle_s: float, axis: int = 3) -> dict[int, float]:
    """Times (s) of the points 1-5 that split a limited-wheel turn into the segments of
    seed 001 (text of its Figs. 3-5): 1 the start (torque at its limit), 2 the wheel
    reaches its momentum limit, 3 the coasting ends (the braking torque starts), 4 the
    braking torque leaves its limit (the final transient begins), 5 settled. Points
    whose event does not happen are left out."""
    d = df[df["axis"] == axis]
    t = d["t_s"].to_numpy(dtype=float)
    h = np.abs(d["momentum_Nms"].to_numpy(dtype=float))
    m = np.abs(d["torque_Nm"].to_numpy(dtype=float))
    h_max = d["momentum_max_Nms"].to_numpy(dtype=float)
    m_max = d["torque_max_Nm"].to_numpy(dtype=float)
    out = {1: float(t[0])}
    full = np.flatnonzero(h >= 0.999 * h_max)
    if full.size:
        out[2], out[3] = float(t[full[0]]), float(t[full[-1]])
        braking = np.flatnonzero((m >= 0.999 * m_max) & (t > out[3]))
        if braking.size:
            out[4] = float(t[braking[-1]])
    if np.isfinite(settle_s):
        out[5] = float(settle_s)
    return out


def mark_points(ax, points: dict[int, float], only=None) -> None:
    """Thin vertical lines at the points 1-5, numbered at the top of the panel."""
    for k, t in points.items():
        if only is not None and k not in only:
            continue
        ax.axvline(
            t,
            color=fs.REFERENCE,
            lw=0.7,
            ls=(0, (1, 2)),
            label="points 1-5: the paper's segments, found in our run",
        )
        ax.annotate(str(k), (t, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -10),
                    textcoords="offset points", fontsize=9, fontweight="bold")  # fmt: skip
