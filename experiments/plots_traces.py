"""The figures of trace files (``--trace``; :mod:`kalman_vs_infoset.experiments.traces`):
what ``kvi plot`` draws, and what the commands draw for the traces they write.

Intercept traces give, per traced run, the seed's Fig. 3-style control processes of each
estimator (one column per noise) and, with several estimators, their forecast-miss
intervals overlaid per noise; a trace with a sets file beside it also gives the set in
3-D, 2-D slices and an animation. Attitude traces give their time histories.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.results import TRACE_DIR, existing_sidecar

NOISE_ORDER = ("random", "game", "bias", "none")
#: the columns the figures of an intercept trace and of its sets file read
STEP_COLUMNS = (
    "scenario", "estimator", "noise", "run", "step", "t_s", "channel", "alpha_true_rad",
    "alpha_meas_rad", "alpha_err_rad", "alpha_bound_rad", "forecast_lo_m", "forecast_hi_m",
    "forecast_true_m", "truth_inside", "impulse_mps", "fuel_mps", "miss_m", "x_true_m",
    "zem_true_m",
)  # fmt: skip
SET_COLUMNS = ("run", "step", "t_s", "phase", "channel", "estimator", "x_m", "alpha_rad", "zem_m")


def _read_table(path: Path, what: str) -> pd.DataFrame:
    try:
        return pd.read_parquet(path)
    except Exception as exc:  # missing, truncated or not Parquet
        raise InputError(f"{path}: cannot read {what} ({type(exc).__name__})") from None


def _missing(df: pd.DataFrame, path: Path, needed, what: str) -> None:
    """One line naming the first column of ``needed`` that ``df`` lacks, if any."""
    lacking = [c for c in needed if c not in df.columns]
    if lacking:
        raise InputError(
            f"{path}: {what} without its column {lacking[0]!r} (rewrite it with --trace)"
        )


def _damaged(df: pd.DataFrame, path: Path, what: str, names=(), numbers=()) -> None:
    """One line naming the first column of ``names`` with an empty cell, or of
    ``numbers`` with a value that is not a finite number, if any (a trace the package
    wrote has none: a damaged file, refused before the first figure)."""
    for col in names:
        if df[col].isna().any():
            raise InputError(f"{path}: {what} with an empty {col!r} (rewrite it with --trace)")
    for col in numbers:
        values = pd.to_numeric(df[col], errors="coerce").to_numpy(dtype=float)
        if not np.isfinite(values).all():
            raise InputError(
                f"{path}: {what} whose {col!r} holds a value that is not a finite number "
                "(rewrite it with --trace)"
            )


def _read(path: Path) -> pd.DataFrame:
    df = _read_table(path, "a trace")
    if not ({"run", "step"} <= set(df.columns) and ({"channel", "axis"} & set(df.columns))):
        raise InputError(f"{path}: not a trace (written by --trace: run, step, channel or axis)")
    if "channel" in df:
        _missing(df, path, STEP_COLUMNS, "an intercept trace")
    if not len(df):
        raise InputError(f"{path}: a trace without steps (nothing to draw)")
    what = "an intercept trace" if "channel" in df else "an attitude trace"
    labels = ("scenario", "estimator", "noise", "channel") if "channel" in df else ()
    _damaged(df, path, what, names=labels, numbers=("run", "step", "t_s"))
    if "axis" in df and not (df["axis"] == 1).any():  # its figures draw axis 1's rows
        raise InputError(f"{path}: an attitude trace without the rows of axis 1 (rewrite it "
                         "with --trace)")  # fmt: skip
    return df


def _paper_from_json(path: Path) -> dict[str, tuple[Any, ...]] | None:
    table = path.with_name(path.name.replace("-trace.parquet", ".parquet"))
    if path.parent.name == TRACE_DIR:  # the results table is in the folder above
        table = path.parent.parent / table.name
    try:
        ref = json.loads(existing_sidecar(table).read_text())["scenario"]["reference"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    label = ref.get("label") or "paper"
    return {
        "random": (ref.get("miss_random_m"), ref.get("fuel_random_mps"), label),
        "game": (ref.get("miss_game_m"), ref.get("fuel_game_mps"), label),
    }


def _noises(df: pd.DataFrame) -> list[str]:
    present = list(dict.fromkeys(df["noise"]))
    return sorted(present, key=lambda n: NOISE_ORDER.index(n) if n in NOISE_ORDER else 99)


def plot_files(
    paths, paper=None, out: Path | None = None, animation: bool = True, before_drawing=None
) -> list[Path]:
    """Draw every figure of the traces ``paths``; returns the files written.
    ``before_drawing()`` runs once every input is read and checked (``kvi plot`` makes
    and probes its ``--out`` there, so a refused input leaves no folder behind)."""
    from kalman_vs_infoset.experiments import plots_attitude

    paths = [Path(p) for p in paths]
    if not paths:
        return []
    out = Path(out) if out is not None else paths[0].parent
    frames = [_read(p) for p in paths]
    # every input read and checked before the first figure: a damaged or incomplete
    # sets file is refused before any figure is drawn (they were drawn, then refused)
    set_tables = [_read_sets(p) for p in paths]
    if before_drawing is not None:
        before_drawing()
    files: list[Path] = []
    for path, df in zip(paths, frames, strict=True):
        if "axis" in df:
            stem = out / path.name.replace("-trace.parquet", "-history")
            runs = [g for _, g in df.groupby("run")]
            files += fs.save(plots_attitude.time_histories(runs, _attitude_title(df)), stem)
    steps = [df for df in frames if "channel" in df]
    if not steps:
        return files
    # each scenario's own printed numbers (its results' description): the traces of a
    # scenario's --set variant may carry another reference
    first_path: dict[str, Path] = {}
    for path, frame in zip(paths, frames, strict=True):
        if "channel" in frame:
            first_path.setdefault(str(frame["scenario"].iloc[0]), path)
    df = pd.concat(steps, ignore_index=True)
    if "seed" not in df:
        df = df.assign(seed=None)
    # traces of other scenarios (e.g. --set overrides) or seeds in one folder are drawn
    # apart: their runs share numbers, not truths
    for (name, seed), group in df.groupby(["scenario", "seed"], dropna=False, sort=True):
        tag = "" if pd.isna(seed) else f"-s{int(seed)}"
        marks = paper if paper is not None else _paper_from_json(first_path[str(name)])
        files += _step_figures(group, str(name), tag, out, marks)
    for path, steps_df, sets in zip(paths, frames, set_tables, strict=True):
        if sets is not None:
            files += _set_figures(path, steps_df, sets, out, animation)
    return files


def _attitude_title(df: pd.DataFrame) -> str:
    """The title of an attitude trace's time histories, in words (as ``kvi attitude``
    titles them, with the trace's estimator and noise): one figure per trace file, so
    the title says whose it is."""
    from kalman_vs_infoset.experiments import plots_attitude

    first = df.iloc[0]
    noise = str(first["noise"]) if "noise" in df else None
    seed = first["seed"] if "seed" in df else None
    return plots_attitude.history_title(
        str(first["scenario"]), str(first["controller"]) if "controller" in df else None,
        sorted(int(r) for r in df["run"].unique()),
        None if seed is None or pd.isna(seed) else int(seed),
        fs.words(str(first["estimator"]), noise),
    )  # fmt: skip


def _step_figures(df: pd.DataFrame, name: str, tag: str, out: Path, paper) -> list[Path]:
    """One scenario's and seed's figures; their names carry what distinguishes the run
    (estimator, noises, seed ``tag``, run), so drawing another seed never replaces them.
    Each figure shows the estimators and noises that traced the run (a run traced by
    one estimator only, or failed for another, is drawn with the traces it has)."""
    from kalman_vs_infoset.experiments import plots_intercept

    files: list[Path] = []
    for run in sorted(df["run"].unique()):
        at = df[df["run"] == run]
        for est in dict.fromkeys(at["estimator"]):
            d = at[at["estimator"] == est]
            noises = _noises(d)
            fig = plots_intercept.control_processes(d, int(run), str(est), noises, paper=paper)
            # '+' between noises, as the other figure names (a comma is awkward in a shell)
            stem = f"{name}-{est}-{'+'.join(noises)}{tag}-run{run}-processes"
            files += fs.save(fig, out / stem)
        for noise in _noises(at):
            by_noise = at[at["noise"] == noise]
            if by_noise["estimator"].nunique() > 1:
                fig = plots_intercept.estimator_overlay(by_noise, int(run), noise)
                files += fs.save(fig, out / f"{name}-{noise}{tag}-run{run}-overlay")
    return files


def _read_sets(path: Path) -> pd.DataFrame | None:
    """The sets file beside the trace ``path``, checked (None when there is none)."""
    sets_path = path.with_name(path.name.replace("-trace.parquet", "-trace-sets.parquet"))
    if not sets_path.exists():
        return None
    sets = _read_table(sets_path, "the sets of a trace")
    _missing(sets, sets_path, SET_COLUMNS, "the sets of a trace")
    # the vertices of polygons: finite wherever the package wrote them
    numbers = ("run", "step", "t_s", "x_m", "alpha_rad", "zem_m")
    _damaged(sets, sets_path, "the sets of a trace", ("phase", "channel", "estimator"), numbers)
    return sets


def _set_figures(
    path: Path, steps: pd.DataFrame, sets: pd.DataFrame, out: Path, animation: bool
) -> list[Path]:
    """The set figures of the trace ``path`` (its steps ``steps``, its sets ``sets``)."""
    from kalman_vs_infoset.experiments import plots_sets

    stem = path.name.replace("-trace.parquet", "")
    files: list[Path] = []
    for run in sorted(sets["run"].unique()):
        s = sets[sets["run"] == run]
        prior = s[s["phase"] == "prior"]
        if len(prior):  # t = 1 s when recorded (the seed's Fig. 4), else the last prior step
            at = prior[prior["t_s"] == 1.0]
            step = int((at if len(at) else prior)["step"].max())
            # words, not the file stem: scenario, estimator, noise, seed and run
            title = (f"{s['scenario'].iloc[0]}: the set before and after the measurements, "
                     f"{plots_sets.run_words(s, int(run))}")  # fmt: skip
            fig = plots_sets.stacked_3d(s, int(run), step, steps, title=title)
            files += fs.save(fig, out / f"{stem}-run{run}-set3d")
        files += fs.save(plots_sets.slices(s, int(run), steps), out / f"{stem}-run{run}-slices")
        if animation:
            gif = out / f"{stem}-run{run}-set.gif"
            files.append(plots_sets.animate(s, int(run), gif, steps))
    return files
