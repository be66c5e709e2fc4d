"""CDF plots of miss and fuel (matplotlib, Agg backend), PNG and SVG."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display needed (CI, clusters)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

PANELS = (("miss_m", "miss distance, m"), ("fuel_mps", "fuel (sum of |impulses|), m/s"))


def _cdf(ax, values: np.ndarray, label: str, **style) -> None:
    v = np.sort(values[np.isfinite(values)])
    if len(v) == 0:
        return
    p = np.arange(1, len(v) + 1) / len(v)
    ax.step(
        np.concatenate([[v[0]], v]), np.concatenate([[0.0], p]), where="post", label=label, **style
    )


def cdf_figure(
    df: pd.DataFrame,
    group_cols: Sequence[str],
    title: str,
    references: Mapping[str, Sequence[tuple[float, str]]] | None = None,
    log_miss: bool = True,
):
    """One panel per metric (miss, fuel), one CDF curve per group of ``group_cols``.

    ``references`` maps a metric column to ``(value, label)`` marks drawn as
    vertical lines (the paper's numbers, lower bounds).
    """
    ok = df[df["status"] == "ok"] if "status" in df else df
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    styles = ["-", "--", "-.", ":"]
    for ax, (col, xlabel) in zip(axes, PANELS, strict=True):
        for i, (key, grp) in enumerate(ok.groupby(list(group_cols), sort=True)):
            key = key if isinstance(key, tuple) else (key,)
            label = " / ".join(str(k) for k in key) + f" (n={len(grp)})"
            _cdf(ax, grp[col].to_numpy(dtype=float), label, linestyle=styles[i % 4], lw=1.6)
        for j, (value, label) in enumerate((references or {}).get(col, ())):
            ax.axvline(value, color=f"C{7 + j % 3}", lw=1.0, ls=":", alpha=0.9)
            ax.text(value, 0.02 + 0.08 * j, " " + label, rotation=90, fontsize=7, va="bottom")
        if col == "miss_m" and log_miss and (ok[col] > 0).all() and len(ok):
            ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("fraction of runs (CDF)")
        ax.set_ylim(0, 1.02)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper left")
    fig.suptitle(title, fontsize=10)
    return fig


def sweep_figure(table: pd.DataFrame, key: str, title: str):
    """Mean miss and mean fuel against a swept value: one colour per estimator, one
    marker and line style per noise.

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
    colours = {e: f"C{i}" for i, e in enumerate(dict.fromkeys(table["estimator"]))}
    looks = ["o-", "s--", "^-.", "D:"]
    noises = {n: looks[i % 4] for i, n in enumerate(dict.fromkeys(table["noise"]))}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    groups = table.assign(_x=x).groupby(["estimator", "noise"], sort=False)
    for ax, (col, ylabel) in zip(axes, PANELS, strict=True):
        for (est, noise), grp in groups:
            grp = grp.sort_values("_x")
            ax.plot(grp["_x"], grp[f"{col}_mean"], noises[noise], color=colours[est], lw=1.5,
                    label=f"{est} / {noise}")  # fmt: skip
        if numeric and (x > 0).all() and x.max() >= 10 * x.min():
            ax.set_xscale("log")
        if not numeric:
            ax.set_xticks(range(len(labels)), labels, fontsize=7)
        if col == "miss_m" and (table[f"{col}_mean"] > 0).all():
            ax.set_yscale("log")
        ax.set_xlabel(key)
        ax.set_ylabel(f"{ylabel}, mean over runs")
        ax.grid(True, alpha=0.3)
    axes[1].legend(fontsize=7, loc="best", ncol=2)
    fig.suptitle(title, fontsize=10)
    return fig


def save(fig, path_stem: Path) -> list[Path]:
    """Write ``<stem>.png`` and ``<stem>.svg``; returns the paths."""
    path_stem.parent.mkdir(parents=True, exist_ok=True)
    # appended, not with_suffix: names may hold dots (--set suffixes, "fig5.v2")
    out = [path_stem.parent / f"{path_stem.name}.{ext}" for ext in ("png", "svg")]
    for p in out:
        fig.savefig(p, dpi=130)
    plt.close(fig)
    return out
