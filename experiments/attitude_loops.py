"""The attitude experiments as typed objects: one :class:`AttitudeLoop` per simulation.

Each loop module (:mod:`experiments.attitude_rw`, :mod:`experiments.attitude_cmg`,
:mod:`experiments.attitude_gyrostat`) declares its ``LOOP``: the controllers it runs,
its chunk size, and the functions that validate a scenario, simulate a chunk of runs,
summarise the rows and replay one run with recording. :data:`LOOPS` is the one table
from a controller to the module declaring its loop; the module is imported only when
its controller is asked for (:func:`loop_of`), so a loop whose module cannot be imported
is "not available" in one line, and the others still run.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from kalman_vs_infoset.experiments.errors import InputError, built_or_refused

if TYPE_CHECKING:  # the traces are tables; the command line imports this table to parse
    import pandas as pd

#: prepare(source, scenario, controller, noise) -> the validated set-up of the runs
Prepare = Callable[[str, Mapping[str, Any], str, str], Any]
#: task(setup, controller, noise, estimator, seeds) -> one row per seed
Task = Callable[..., list[dict[str, Any]]]
#: summarise(setup, controller, noise, estimator, runs, seed, ok_rows, failures) -> JSON
Summarise = Callable[..., dict[str, Any]]
#: trace(setup, controller, noise, estimator, seed_seq) -> long-format rows of one run
Trace = Callable[..., "pd.DataFrame"]
#: estimator(setup, noise, name) -> the runs' estimator, built as a run builds it
BuildEstimator = Callable[[Any, str, str], Any]


@dataclass(frozen=True)
class AttitudeLoop:
    """One attitude simulation as the ``attitude`` command runs it.

    Parameters
    ----------
    name : str
        What it simulates (messages).
    controllers : tuple of str
        The controllers it runs (the scenario's ``controller`` or ``--controller``).
    chunk : int
        Runs per task of the runner (the vectorised loops batch their runs).
    prepare, task, summarise, trace
        The validation, the runs of a chunk, the JSON of docs/models.md §3.1 from the
        finished rows, and one run replayed with recording
        (:mod:`experiments.attitude_traces`).
    estimator
        The runs' estimator from the set-up, the noise and the estimator's name, as a
        run builds it (:func:`check_plug_ins` builds plug-ins with it up front).
    performance : tuple of str
        The row's measures of the turn's end (NaN for a run whose loop diverged).
    controller_columns : mapping of str to tuple of str
        Columns only some controllers' rows have (the LQR's Lyapunov check).
    """

    name: str
    controllers: tuple[str, ...]
    chunk: int
    prepare: Prepare
    task: Task
    summarise: Summarise
    trace: Trace
    estimator: BuildEstimator
    performance: tuple[str, ...]
    controller_columns: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def columns(self, controller: str) -> tuple[str, ...]:
        """The result columns of every run of ``controller`` (docs/results.md): a table
        of failed runs gets them as NaN, so selecting one does not raise KeyError."""
        extra = self.controller_columns.get(controller, ())
        return (*self.performance, *extra, *COUNTS)


#: the columns of every attitude run's row besides its loop's measures: the set's
#: guarantee and emptiness counts, and whether (when) the loop diverged
COUNTS = ("truth_outside", "empty_steps", "unbounded_steps", "mean_knowledge_bound_deg",
          "diverged", "diverged_time_s")  # fmt: skip

#: controller -> the module declaring its :class:`AttitudeLoop` as ``LOOP``
LOOPS: dict[str, str] = {
    "pd": "kalman_vs_infoset.experiments.attitude_rw",
    "lqr": "kalman_vs_infoset.experiments.attitude_rw",
    "energy": "kalman_vs_infoset.experiments.attitude_cmg",
    "euler": "kalman_vs_infoset.experiments.attitude_cmg",
    "game": "kalman_vs_infoset.experiments.attitude_gyrostat",
}


def loop_of(controller: str) -> AttitudeLoop:
    """The loop running ``controller`` (``InputError`` of one line if unknown or not
    available)."""
    if controller not in LOOPS:
        raise InputError(f"unknown controller '{controller}' (allowed: {', '.join(LOOPS)})")
    name = LOOPS[controller]
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name != name:
            raise
        raise InputError(f"controller {controller} is not available") from None
    loop = module.LOOP
    if not isinstance(loop, AttitudeLoop) or controller not in loop.controllers:
        raise InputError(f"controller {controller} is not available")
    return loop


def same_loop(a: str, b: str) -> bool:
    """Whether controllers ``a`` and ``b`` are run by one simulation (one scenario kind)."""
    return LOOPS.get(a) == LOOPS.get(b)


def controllers_like(controller: str) -> str:
    """The controllers of ``controller``'s simulation, quoted (messages)."""
    return ", ".join(repr(k) for k, v in LOOPS.items() if v == LOOPS[controller])


def check_plug_ins(loop: AttitudeLoop, setups: Mapping[str, Any], estimators) -> None:
    """Build each plug-in estimator of ``estimators`` once for each noise's set-up, as
    the runs build it: one that raises (options its factory refuses, say) is refused
    here in one line (:class:`InputError`, exit status 2), where every run would fail
    with the same error. The package's own estimators are not built up front (their
    options models validate what they accept)."""
    from kalman_vs_infoset.experiments.provenance import plug_ins

    for name in plug_ins("attitude", estimators):
        for noise, setup in setups.items():
            what = f"estimator {name!r} cannot be built for the {loop.name} runs (options "
            what += f"[estimator_options.{name}], noise {noise})"
            built_or_refused(what, loop.estimator, setup, noise, name)
