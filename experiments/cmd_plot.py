"""``kvi plot TRACE.parquet [...]``: the figures of traces.

Every file is a trace written by ``--trace`` (:mod:`experiments.traces`). Intercept
traces (several at once: e.g. the estimators and noises of one ``compare``) give, per
traced run, the seed's Fig. 3-style control processes of each estimator (one column per
noise) and, when several estimators are given, their forecast-miss intervals overlaid
per noise; a trace with a sets file beside it (``-trace-sets.parquet``) also gives the
set in 3-D at ``t = 1 s`` before and after the measurements (the seed's Fig. 4), 2-D
pictures at six times and an animation (GIF). Attitude traces give the time histories
of :func:`kalman_vs_infoset.experiments.plots_attitude.time_histories`. The paper's printed miss and
fuel are marked when the results' description (``_meta/``) holds a ``[reference]``.
Figures are PNG and SVG beside the first trace (or in ``--out``). A folder stands for
the traces under it: ``kvi plot results/kp_fig3`` redraws every trace a command wrote
to that ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.errors import InputError


def plot_files(paths: list[Path], **kwargs: Any) -> list[Path]:
    """The figures of the traces ``paths``
    (:func:`kalman_vs_infoset.experiments.plots_traces.plot_files`)."""
    # imported when drawing, not with the command: declaring its arguments needs no plots
    from kalman_vs_infoset.experiments.plots_traces import plot_files as draw

    return draw(paths, **kwargs)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "traces", nargs="+", help="trace files (*-trace.parquet), or folders holding them"
    )
    p.add_argument("--out", help="folder of the figures (default: beside the first trace)")
    p.add_argument("--no-animation", action="store_true", help="no GIF of the set")


def _expand(arguments: list[str]) -> list[Path]:
    """The trace files named, a folder standing for those under it (a results ``--out``
    keeps them in ``_traces/``)."""
    out = []
    for p in map(Path, arguments):
        if p.is_dir():
            found = sorted(p.rglob("*-trace.parquet"))
            if not found:
                raise InputError(f"{p}: no trace files in this folder (write them with --trace)")
            out += found
        else:
            out.append(p)
    return out


def run(args) -> dict[str, Any]:
    paths = []
    for p in _expand(args.traces):
        if p.name.endswith("-trace-sets.parquet"):  # `plot *trace*` names both files
            step = p.with_name(p.name.replace("-trace-sets.parquet", "-trace.parquet"))
            if not step.is_file():
                raise InputError(f"{p}: the sets of a trace; its {step.name} is missing")
            p = step
        if not p.is_file():
            raise InputError(f"{p}: no such trace file")
        if p not in paths:
            paths.append(p)
    # the figures are this command's only output: a folder it cannot write is refused
    # before any drawing (not skipped figure by figure), and made only once the traces
    # are read and checked (a refused trace leaves no empty folder)
    out = options.out_folder(args.out, paths[0].parent)
    flag = "--out" if args.out else "the traces' folder"
    files = plot_files(paths, out=out, animation=not args.no_animation,
                       before_drawing=lambda: options.writable_folder(out, flag))  # fmt: skip
    return {"traces": [str(p) for p in paths], "files": [str(f) for f in files]}


def render(result: dict[str, Any]) -> str:
    return "figures:\n" + "\n".join("  " + f for f in result["files"])
