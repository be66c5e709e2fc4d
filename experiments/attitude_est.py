"""Attitude loops as consumers of estimators (SPEC 2.5): shared plumbing for the loops.

Every attitude loop (:mod:`experiments.attitude_rw`, :mod:`experiments.attitude_cmg`,
:mod:`experiments.attitude_gyrostat`) runs the estimator registered under a name
(:mod:`estim.registry`, problem ``"attitude"``: ``perfect``, ``ukf``, ``box`` and any
other registered one) through :class:`EstimatorLoop`:

per control step ``predict`` over the period with the known inputs held over it
(delivered torque, momentum interval), then ``update`` with the new measurement; the
controller reads ``centre()`` = ``(q, w)`` per run; ``truth_outside`` counts the
(run, step) pairs where the truth is not in the belief (for ``perfect`` that is every
noisy step: a point is not a set). Measurement errors are uniform within the model's
bounds (:func:`estim.attitude_model.draw_measurement`).

Also: Monte Carlo outputs (per-run Parquet table, CDF figures PNG+SVG of settle time,
energy index and final error, one curve per controller x estimator x noise).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from estim import registry
from estim.attitude_model import (
    AttitudeBelief,
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
)
from estim.base import Estimator
from experiments.errors import InputError
from experiments.files import atomic_write
from experiments.provenance import code_identity


def resolve_estimators(arg: str | None, scenario_default: str | None, noise: str) -> list[str]:
    """``--estimator`` (comma list) or the scenario's, else ``perfect`` (noise none) / ``box``."""
    if arg is None:
        arg = scenario_default or ("perfect" if noise == "none" else "box")
    names = [s.strip() for s in str(arg).split(",") if s.strip()]
    allowed = registry.names("attitude")
    bad = [n for n in names if n not in allowed]
    if not names or bad:
        raise InputError(f"--estimator must be one or more of {', '.join(allowed)}, got '{arg}'")
    return list(dict.fromkeys(names))


@dataclass(frozen=True)
class EstimatorLoop:
    """One registered attitude estimator run over a batch of runs."""

    name: str
    model: AttitudeModel
    estimator: Estimator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        try:
            reg = registry.get("attitude", self.name)
        except KeyError as exc:
            raise ValueError(exc.args[0]) from None
        object.__setattr__(self, "estimator", reg.build(None, self.model))

    def start(self, meas: AttitudeMeasurement) -> AttitudeBelief:
        return self.estimator.initial(AttitudePrior(meas))

    def step(self, belief, control: AttitudeControl, dt_s: float, meas: AttitudeMeasurement):
        """``predict`` over ``dt_s`` with the inputs held over it, ``update`` with ``meas``."""
        est = self.estimator
        return est.update(est.predict(belief, dt_s, control), meas)

    @staticmethod
    def centre(belief: AttitudeBelief) -> np.ndarray:
        """``(q, w)`` per run, ``(R, 7)``."""
        return np.atleast_2d(belief.centre())

    @staticmethod
    def inside(belief: AttitudeBelief, truth: np.ndarray) -> np.ndarray:
        """Per run: truth ``(q, w, ...)`` in the belief."""
        return belief.inside(np.atleast_2d(truth)[:, 0:7])

    @staticmethod
    def empty_steps(belief: AttitudeBelief) -> np.ndarray:
        return belief.empty_counts

    @staticmethod
    def attitude_bound_rad(belief: AttitudeBelief) -> np.ndarray:
        return belief.attitude_bound_rad()


PANELS = (
    ("settle_time_s", "settle time, s"),
    ("energy_N2m2s", "energy index sum M^T M dt, N^2 m^2 s"),
    ("final_angle_deg", "final attitude error, deg"),
)


def write_outputs(out_dir: Path, stem: str, rows: list[dict[str, Any]], meta: dict) -> list[str]:
    """Per-run Parquet table (+ resolved scenario JSON) and CDF figures (PNG, SVG)."""
    from experiments import plots  # matplotlib only when writing files

    out_dir.mkdir(parents=True, exist_ok=True)
    df = pd.DataFrame(rows)
    table = out_dir / f"{stem}-runs.parquet"
    atomic_write(table, lambda tmp: df.to_parquet(tmp, index=False))
    text = json.dumps({**meta, "code": code_identity()}, indent=1, default=str)
    atomic_write(out_dir / f"{stem}-scenario.json", lambda tmp: Path(tmp).write_text(text))
    fig, axes = plots.plt.subplots(1, 3, figsize=(15, 4.2), constrained_layout=True)
    styles = ["-", "--", "-.", ":"]
    groups = list(df.groupby(["controller", "estimator", "noise"], sort=True))
    for ax, (col, label) in zip(axes, PANELS, strict=True):
        for i, (key, grp) in enumerate(groups):
            name = " / ".join(key) + f" (n={len(grp)})"
            plots._cdf(ax, grp[col].to_numpy(dtype=float), name, linestyle=styles[i % 4], lw=1.6)
        ax.set_xlabel(label)
        ax.set_ylabel("fraction of runs (CDF)")
        ax.set_ylim(0, 1.02)
        ax.grid(True, alpha=0.3)
        vals = df[col].to_numpy(dtype=float)
        vals = vals[np.isfinite(vals)]
        if (
            col == "final_angle_deg"
            and vals.size
            and vals.min() > 0
            and vals.max() > 20 * vals.min()
        ):
            ax.set_xscale("log")
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(fontsize=8, loc="lower right")
    fig.suptitle(f"{stem}: controller / estimator / noise", fontsize=10)
    files = plots.save(fig, out_dir / f"{stem}-cdf")
    return [str(table), *(str(f) for f in files)]


def comparison_figure(tables: dict[str, list[Path]], out_stem: Path) -> list[Path]:
    """README figure: one row per scenario, columns settle time / energy / final error,
    one CDF curve per estimator x noise, from the per-run Parquet tables."""
    from experiments import plots

    fig, axes = plots.plt.subplots(
        len(tables), 3, figsize=(15, 3.3 * len(tables)), constrained_layout=True, squeeze=False
    )
    styles = {"perfect": ":", "ukf": "--", "box": "-"}
    colours = {"random": "C0", "game": "C3", "none": "C2"}
    for row, (name, paths) in zip(axes, tables.items(), strict=True):
        df = pd.concat([pd.read_parquet(p) for p in paths], ignore_index=True)
        for ax, (col, label) in zip(row, PANELS, strict=True):
            for (est, noise), grp in df.groupby(["estimator", "noise"], sort=True):
                plots._cdf(
                    ax, grp[col].to_numpy(dtype=float), f"{est} / {noise}",
                    linestyle=styles.get(est, "-"), color=colours.get(noise, "k"), lw=1.5,
                )  # fmt: skip
            vals = df[col].to_numpy(dtype=float)
            vals = vals[np.isfinite(vals)]
            if col != "settle_time_s" and vals.size and vals.min() > 0:
                if vals.max() / vals.min() > 20:
                    ax.set_xscale("log")
            ax.set_xlabel(label)
            ax.set_ylabel("fraction of runs")
            ax.set_ylim(0, 1.02)
            ax.grid(True, alpha=0.3)
        ctrl = ", ".join(sorted(set(df["controller"])))
        row[0].set_title(f"{name} ({ctrl})", loc="left", fontsize=9)
        if row[0].get_legend_handles_labels()[0]:
            row[0].legend(fontsize=7, loc="lower right")
    return plots.save(fig, out_stem)
