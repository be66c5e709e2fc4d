"""CDF plots of miss and fuel, and sweep plots (matplotlib, Agg backend), PNG and SVG.

Styled by :mod:`experiments.figstyle`: colour = estimator, line style = noise, line
width = variant (e.g. with the range finder); reference marks are labelled lines
(black dotted: the paper's numbers, grey: our bounds).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments.figstyle import plt  # noqa: F401 - re-exported for older callers

PANELS = (("miss_m", "miss distance, m"), ("fuel_mps", "fuel (sum of |impulses|), m/s"))
CDF_LABEL = "fraction of runs (CDF), -"
#: above this many legend entries in a panel (curves and reference marks) the legend
#: goes below the panels (4 columns): with nine curves (3 estimators x 3 noises) a
#: legend inside the fuel panel covered two filters' curves
CROWDED_CURVES = 6


def _cdf(ax, values: np.ndarray, label: str, **style) -> None:
    """The empirical CDF of ``values`` (``Axes.ecdf``: a step from 0 at the smallest
    value to 1 at the largest). NaN is left out; ``+inf`` (a run that never settled)
    counts as larger than every value, so the curve ends at the share of finite runs
    instead of claiming that every run got there."""
    values = values[~np.isnan(values)]
    v = np.sort(values[np.isfinite(values)])
    if len(v) == 0:
        return
    if len(v) == len(values):
        ax.ecdf(v, label=label, **style)
        return
    share = np.arange(1, len(v) + 1) / len(values)
    ax.step(np.r_[v[0], v], np.r_[0.0, share], where="post", label=label, **style)


def curve(ax, name: str, rows: pd.DataFrame, col: str, **style) -> None:
    """The CDF curve of the column ``col`` over one group's ``rows`` (every row of the
    group, failed ones included), labelled with what it is drawn over: ``n`` the runs
    with a value (``+inf`` is a value: never settled), then the failed runs and the
    runs without a value (NaN) that it leaves out, when there are any (the curve reached
    1 over the others while the label counted the whole group), of which those of runs
    whose closed loop diverged (an attitude table's ``diverged``) by that name; runs
    that diverged and still have a value (an intercept's miss and fuel) are counted in
    ``n``, "of which k diverged"."""
    failed = int((rows["status"] != "ok").sum()) if "status" in rows else 0
    ok = rows[rows["status"] == "ok"] if "status" in rows else rows
    # (a table whose every run failed has no column of results)
    values = ok[col].to_numpy(dtype=float) if col in ok else np.empty(0)
    nan = np.isnan(values)
    # an attitude run whose loop diverged has no value for its turn's end: said so
    known = "diverged" in ok and col in ok
    diverged = ok["diverged"].to_numpy(dtype=float) > 0 if known else np.zeros_like(nan)
    missing, gone = int(np.sum(nan & ~diverged)), int(np.sum(nan & diverged))
    # an intercept run that diverged has values (a miss of kilometres, no fuel): drawn,
    # but said, or its curve reads as an ordinary result
    drawn_diverged = int(np.sum(~nan & diverged))
    notes = [f"n={len(values) - missing - gone}"]
    notes[0] += f" of which {drawn_diverged} diverged" if drawn_diverged else ""
    notes += [f"{failed} failed"] if failed else []
    notes += [f"{gone} diverged"] if gone else []
    notes += [f"{missing} without a value"] if missing else []
    label = f"{name} ({', '.join(notes)})"
    if len(values) == missing + gone:  # nothing to draw: the legend still says why
        ax.plot([], [], label=label, **style)
        return
    _cdf(ax, values, label, **style)


def _words(column: str, value: object) -> str:
    """A group key as a legend shows it: an estimator by its registration's label (the
    information set, UKF, a plug-in's own words), anything else as it is."""
    return fs.words(str(value)) if column == "estimator" else str(value)


def group_style(keys: Mapping[str, object], df: pd.DataFrame, variants: Sequence) -> dict:
    """Colour from the group's (or the table's) estimator, line style from its noise,
    line width from its variant's position in ``variants``."""
    est = keys.get("estimator", df["estimator"].iloc[0] if "estimator" in df else "")
    noise = keys.get("noise", df["noise"].iloc[0] if "noise" in df else "")
    style = fs.line(str(est), str(noise))
    if "variant" in keys and len(variants) > 1:
        style["lw"] = 1.3 + 1.5 * list(variants).index(keys["variant"])
    return style


def cdf_figure(
    df: pd.DataFrame,
    group_cols: Sequence[str],
    title: str,
    references: Mapping[str, Sequence[tuple[float, str]]] | None = None,
    log_miss: bool = True,
):
    """One panel per metric (miss, fuel), one CDF curve per group of ``group_cols``.

    ``references`` maps a metric column to ``(value, label)`` marks drawn as labelled
    vertical lines (the paper's numbers when the label starts with "seed" or "paper":
    black; our lower bounds: grey).
    """
    ok = df[df["status"] == "ok"] if "status" in df else df
    n_curves = df.groupby(list(group_cols)).ngroups if len(df) else 0
    # the entries of a panel's legend: its curves and its reference marks (fig5's four
    # curves and three marks put a legend inside the fuel panel, over the game curves)
    n_marks = max((len(v) for v in (references or {}).values()), default=0)
    crowded = n_curves + n_marks > CROWDED_CURVES
    # the figure legend's rows below the panels (4 columns): every curve and every mark
    entries = n_curves + sum(len(v) for v in (references or {}).values())
    rows = -(-entries // 4)
    fig, axes = fs.figure(1, 2, size=(11, 4.4 + (0.17 * rows if crowded else 0.0)))
    variants = sorted(df["variant"].unique()) if "variant" in df else []
    for ax, (col, xlabel) in zip(axes[0], PANELS, strict=True):
        for key, grp in df.groupby(list(group_cols), sort=True):
            key = key if isinstance(key, tuple) else (key,)
            keys = dict(zip(group_cols, key, strict=True))
            name = " / ".join(_words(c, k) for c, k in keys.items())
            curve(ax, name, grp, col, **group_style(keys, df, variants))
        # the paper's marks (its random and game runs, say) one line style each
        paper_ls = iter((":", "-.", (0, (5, 2, 1, 2, 1, 2)), (0, (1, 4))))
        unit = xlabel.rsplit(", ", 1)[1]  # the axis's unit: the legend holds both panels'
        for value, label in (references or {}).get(col, ()):
            paper = label.startswith(("seed", "paper"))
            ax.axvline(value, color=fs.PAPER if paper else fs.REFERENCE, lw=1.0,
                       ls=next(paper_ls, ":") if paper else "--",
                       label=f"{label}: {value:.4g} {unit}")  # fmt: skip
        if not len(ok):  # every run failed: the rows say why, the panel says so
            ax.text(0.5, 0.5, "no successful run", ha="center", va="center",
                    transform=ax.transAxes)  # fmt: skip
        elif col == "miss_m" and log_miss and (ok[col] > 0).all():
            ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(CDF_LABEL)
        ax.set_ylim(0, 1.02)
        if not crowded:
            fs.legend(ax, fontsize=7, loc="best")  # where it covers the fewest points
    if crowded:  # one legend below both panels: inside an axis it would hide the curves
        fs.figure_legend(fig, axes[0], fontsize=7, ncol=4)
    fig.suptitle(title, fontsize=10)
    return fig


def sweep_figure(table: pd.DataFrame, key: str, title: str, xlabel: str | None = None):
    """Mean miss and mean fuel against a swept value: one colour per estimator, one
    marker and line style per noise; the x axis reads ``xlabel`` (the swept field's doc
    with its unit), else ``key``.

    ``table`` has one row per (value, estimator, noise) with ``value`` as JSON text
    and the summary columns flattened (``miss_m_mean``, ``fuel_mps_mean``, ...).
    Numeric values are plotted on a numeric axis (logarithmic when positive and
    spanning a decade or more); others (intervals, booleans) one tick each.
    """
    values = [json.loads(v) for v in table["value"]]
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
    labels = list(dict.fromkeys(table["value"]))
    x = (
        np.array(values, dtype=float)
        if numeric
        else np.array([labels.index(v) for v in table["value"]], dtype=float)
    )
    markers = {"random": "o", "game": "s", "bias": "^", "none": "D"}
    fig, axes = fs.figure(1, 2, size=(11, 4.4))
    groups = table.assign(_x=x).groupby(["estimator", "noise"], sort=False)
    for ax, (col, ylabel) in zip(axes[0], PANELS, strict=True):
        for (est, noise), grp in groups:
            grp = grp.sort_values("_x")
            ax.plot(grp["_x"], grp[f"{col}_mean"], marker=markers.get(noise, "o"),
                    **fs.line(est, noise), label=f"{fs.words(est)} / {noise}")  # fmt: skip
        if numeric and (x > 0).all() and x.max() >= 10 * x.min():
            ax.set_xscale("log")
        if not numeric:
            ax.set_xticks(range(len(labels)), labels, fontsize=7)
        if col == "miss_m" and (table[f"{col}_mean"] > 0).all():
            ax.set_yscale("log")
        ax.set_xlabel(xlabel or key)
        ax.set_ylabel(f"mean {ylabel}")  # (over the runs of a point: the title's count)
    fs.legend(axes[0, 1], fontsize=7, loc="best", ncol=2)
    fig.suptitle(title, fontsize=10)
    return fig


def save(fig, path_stem: Path) -> list[Path]:
    """Write ``<stem>.png`` and ``<stem>.svg``; returns the paths (:func:`figstyle.save`)."""
    return fs.save(fig, Path(path_stem))
