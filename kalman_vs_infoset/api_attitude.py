"""The attitude loops from Python: :func:`run_attitude` (re-exported by
:mod:`kalman_vs_infoset.api` and the package root).

The runs are the ``kvi attitude`` command's (the same scenario rules, controllers,
estimators and seeds: run ``j`` draws from ``SeedSequence(seed).spawn(runs)[j]``), in
this process and without files, as :func:`kalman_vs_infoset.api.run_engagement` is
for the intercept.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd


def run_attitude(
    scenario: str | Path,
    *,
    controller: str | None = None,
    noise: str = "none",
    estimator: str | None = None,
    runs: int = 1,
    seed: int = 0,
    tables: Mapping[str, Any] | None = None,
    **overrides: Any,
) -> pd.DataFrame:
    """Closed-loop attitude runs, one row per run, as ``kvi attitude`` records them.

    Parameters
    ----------
    scenario : str or pathlib.Path
        A bundled attitude scenario's name (``smallsat_rw``, ``lqr_large_angle``,
        ``resurs_p``, ``gyrostat_game``) or a scenario file.
    controller : str, optional
        ``pd``, ``lqr``, ``energy``, ``euler`` or ``game`` (default: the scenario's).
    noise : {"none", "random", "game"}
        Exact measurements, bounded random errors and disturbances, or the adversary.
    estimator : str, optional
        A registered attitude estimator (:func:`kalman_vs_infoset.api.estimators`
        ``("attitude")``); default: the scenario's (each of a comma list), else the one
        reading the measurement as the state for ``noise="none"`` and the reference set
        otherwise.
    runs : int, default 1
        Number of runs (``>= 1``).
    seed : int, default 0
        The root seed.
    tables : mapping, optional
        Tables of fields to change by name, for a table whose name is taken by an
        argument above: the measurement errors and disturbances of ``[noise]`` are
        ``tables={"noise": {"meas_angle_deg": 0.01}}`` (``noise=`` chooses the noise).
    **overrides
        Tables of fields to change, e.g. ``simulation={"duration_s": 20.0}`` or
        ``estimator_options={"ukf": {"gate_prob": 0.99}}``; validated like the file.

    Returns
    -------
    pandas.DataFrame
        One row per estimator and run: the job's ``scenario``, ``controller``,
        ``estimator``, ``noise`` and ``seed``, ``run``, the loop's columns
        (``docs/results.md``: settle time, energy, final errors, ``truth_outside``, ...)
        and ``status`` (``ok``, or ``failed`` with its ``error`` and NaN in the loop's
        columns, which are there even when every run failed).

    Raises
    ------
    ValueError
        An unknown estimator or noise (naming the allowed ones).
    kalman_vs_infoset.experiments.errors.InputError
        An unknown scenario or controller, or a bad field (one line).

    Examples
    --------
    >>> from kalman_vs_infoset.api import run_attitude
    >>> df = run_attitude("smallsat_rw", noise="random", estimator="box", runs=2,
    ...                   simulation={"duration_s": 20.0})
    >>> len(df), int(df["truth_outside"].sum()), df["status"].tolist()
    (2, 0, ['ok', 'ok'])
    """
    import pandas as pd

    from kalman_vs_infoset._api_args import integer_in, overrides_as_sets, root_seed, with_columns
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.experiments.attitude_request import request
    from kalman_vs_infoset.experiments.runner import batched_task
    from kalman_vs_infoset.experiments.sim.estimator_loop import NOISES

    runs = integer_in(runs, "runs", 1)
    if tables is not None and not isinstance(tables, Mapping):  # "'list' object is not a mapping"
        raise TypeError(f"tables must map table names to their fields, got {tables!r}")
    seed = root_seed(seed, 0)
    if estimator is not None and not isinstance(estimator, str):  # e.g. a list
        raise TypeError(f"estimator must be one name (a str), got {estimator!r}")
    if estimator is not None:
        try:
            registry.get("attitude", estimator)
        except KeyError as exc:  # the registry's line, naming the registered ones
            raise ValueError(exc.args[0]) from None
    if noise not in NOISES:
        raise ValueError(f"noise must be one of {', '.join(NOISES)}, got {noise!r}")
    args = argparse.Namespace(
        scenario=str(scenario),
        overrides=overrides_as_sets({**(tables or {}), **overrides}),
        controller=controller,
        noise=[noise],
        estimators=None if estimator is None else [estimator],
        runs=runs,
        seed=seed,
        out=None,
        via="keyword overrides",
    )
    req = request(args)  # the command's rules and one-line errors
    loop = req.loop
    setup = loop.prepare(req.source, dict(req.scenario), req.controller, noise)
    rows = []
    # every estimator the scenario lists (a comma list), as the command runs them
    for name in req.estimators:

        def simulate(seeds, name=name):
            return loop.task(setup, req.controller, noise, name, seeds)

        # the job's columns, as every run table has them (docs/results.md)
        job = {"scenario": req.name, "controller": req.controller, "estimator": name,
               "noise": noise, "seed": seed}  # fmt: skip
        for start in range(0, runs, loop.chunk):  # the command's batches (memory)
            chunk = list(range(start, min(start + loop.chunk, runs)))
            rows += [{**job, "run": j, **row} for j, row in batched_task(simulate, seed, chunk)]
    return with_columns(pd.DataFrame(rows), loop.columns(req.controller))
