"""Attitude loops as consumers of estimators (SPEC 2.5): shared plumbing for the loops.

Every attitude loop (:mod:`experiments.attitude_rw`, :mod:`experiments.attitude_cmg`,
:mod:`experiments.attitude_gyrostat`) feeds the same estimator wrapper:

* ``perfect``: :class:`estim.base.PerfectEstimator` fed the (noisy) measurement;
* ``ukf``: :class:`estim.attitude_ukf.UkfAttitudeEstimator`;
* ``box``: :class:`estim.attitude_box.BoxAttitudeEstimator` (guaranteed).

Per control step: ``shift`` with the known inputs (delivered torque, momentum
interval), ``predict`` over the period, ``update`` with the new measurement; the
controller reads ``centre()`` = ``(q, w)`` per run; ``truth_outside`` counts the
(run, step) pairs where the truth is not in the belief (for ``perfect`` that is every
noisy step: a point is not a set). Measurement errors are uniform within the model's
bounds (:func:`estim.attitude_model.draw_measurement`).

Also: Monte Carlo outputs (per-run Parquet table, CDF figures PNG+SVG of settle time,
energy index and final error, one curve per controller x estimator x noise).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from estim.attitude_box import BoxAttitudeEstimator
from estim.attitude_model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    qinv,
    qlog,
    qmul,
)
from estim.attitude_ukf import UkfAttitudeEstimator
from estim.base import PerfectEstimator, PointBelief
from experiments.errors import InputError
from experiments.files import atomic_write
from experiments.provenance import code_identity

ESTIMATORS = ("perfect", "ukf", "box")


def resolve_estimators(arg: str | None, scenario_default: str | None, noise: str) -> list[str]:
    """``--estimator`` (comma list) or the scenario's, else ``perfect`` (noise none) / ``box``."""
    if arg is None:
        arg = scenario_default or ("perfect" if noise == "none" else "box")
    names = [s.strip() for s in str(arg).split(",") if s.strip()]
    bad = [n for n in names if n not in ESTIMATORS]
    if not names or bad:
        raise InputError(f"--estimator must be one or more of {', '.join(ESTIMATORS)}, got '{arg}'")
    return list(dict.fromkeys(names))


@dataclass(frozen=True)
class EstimatorLoop:
    """One estimator run over a batch of runs, behind the ``estim.base`` interface."""

    name: str
    model: AttitudeModel

    def __post_init__(self) -> None:
        if self.name not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {ESTIMATORS}, got {self.name!r}")
        est: Any
        if self.name == "box":
            est = BoxAttitudeEstimator(self.model)
        elif self.name == "ukf":
            est = UkfAttitudeEstimator(self.model)
        else:
            est = PerfectEstimator()
        object.__setattr__(self, "estimator", est)

    def start(self, meas: AttitudeMeasurement):
        if self.name == "perfect":
            return PointBelief(np.concatenate([meas.quat, meas.rate_radps], axis=-1))
        return self.estimator.initial(meas)

    def step(self, belief, control: AttitudeControl, dt_s: float, meas: AttitudeMeasurement):
        """``shift`` (known inputs), ``predict`` over ``dt_s``, ``update`` with ``meas``."""
        est = self.estimator
        if self.name == "perfect":
            z = np.concatenate([meas.quat, meas.rate_radps], axis=-1)
            return est.update(est.predict(belief, dt_s), z)
        return est.update(est.predict(est.shift(belief, control), dt_s), meas)

    @staticmethod
    def centre(belief) -> np.ndarray:
        """``(q, w)`` per run, ``(R, 7)``."""
        return np.atleast_2d(belief.centre())

    def inside(self, belief, truth: np.ndarray) -> np.ndarray:
        """Per run: truth ``(q, w, ...)`` in the belief (perfect: equal within 1e-12)."""
        x = np.atleast_2d(truth)
        if self.name != "perfect":
            return belief.inside(x[:, 0:7])
        c = self.centre(belief)
        da = qlog(qmul(qinv(c[:, 0:4]), x[:, 0:4]))
        return np.all(np.abs(np.concatenate([da, c[:, 4:7] - x[:, 4:7]], axis=-1)) <= 1e-12, -1)

    def empty_steps(self, belief) -> np.ndarray:
        runs = self.centre(belief).shape[0]
        return np.asarray(getattr(belief, "n_empty", np.zeros(runs)), dtype=int)

    def attitude_bound_rad(self, belief) -> np.ndarray:
        if self.name == "perfect":
            return np.zeros(self.centre(belief).shape[0])
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
