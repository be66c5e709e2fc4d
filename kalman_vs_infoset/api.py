"""The Python front door: scenarios, one engagement, a Monte Carlo, traces, results.

Everything the command line does for the intercept (``kvi intercept``), callable from
Python and returning plain objects: a typed scenario, an engagement's result, a
:class:`pandas.DataFrame` of runs. The same seeds give the same numbers as the command
line: run ``j`` of a root seed ``s`` draws from ``SeedSequence(s, spawn_key=(j,))``
(:func:`kalman_vs_infoset.experiments.runner.run_seed`), whatever the order, the worker
count or the estimator (paired comparisons). The models are described in
``docs/models.md``; the columns of the tables in ``docs/results.md``.

Examples
--------
>>> import kalman_vs_infoset as kvi
>>> sc = kvi.load_scenario("kp_fig3")
>>> res = kvi.run_engagement(sc, "ukf", "random", run=0)
>>> res.miss_m >= 0.0 and res.fuel_mps > 0.0
True
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from kalman_vs_infoset import _API
from kalman_vs_infoset._api_args import integer_in, overrides_as_sets, root_seed, with_columns
from kalman_vs_infoset.api_attitude import run_attitude as run_attitude
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.registry import Registration
from kalman_vs_infoset.experiments import intercept_runs, runner
from kalman_vs_infoset.experiments import scenario as _scenario
from kalman_vs_infoset.experiments import traces as _traces
from kalman_vs_infoset.experiments.progress import progress_bar
from kalman_vs_infoset.experiments.results import load_results as load_results
from kalman_vs_infoset.experiments.results import read_metadata as read_metadata
from kalman_vs_infoset.experiments.sim import intercept as _intercept
from kalman_vs_infoset.experiments.sim.intercept import EngagementResult
from kalman_vs_infoset.experiments.sim.intercept_config import NOISES as NOISES
from kalman_vs_infoset.experiments.sim.intercept_config import InterceptScenario

__all__ = list(_API)  # the package root re-exports these lazily


def scenarios() -> list[str]:
    """The names of the bundled scenarios (``kvi scenarios`` describes them).

    Returns
    -------
    list of str
        Names accepted by :func:`load_scenario` (and by the commands).

    Examples
    --------
    >>> from kalman_vs_infoset.api import scenarios
    >>> "kp_fig5" in scenarios()
    True
    """
    from kalman_vs_infoset import data

    return data.scenario_names()


def load_scenario(name_or_path: str | Path, **overrides: Any) -> InterceptScenario:
    """An intercept scenario, bundled (by name) or from a TOML file, with overrides.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A bundled scenario's name (:func:`scenarios`) or the path of a scenario file.
    **overrides
        Tables of fields to change, e.g. ``experiment={"runs": 10}`` or
        ``estimator={"infoset": {"n_sections": 40}}``; validated like the file. As with
        the command line's ``--set``, the name gets a ``+key=value`` suffix per field.

    Returns
    -------
    InterceptScenario
        The validated scenario (a frozen pydantic model).

    Raises
    ------
    kalman_vs_infoset.experiments.errors.InputError
        A missing file, an unknown name or field, a value out of bounds (one line).

    Examples
    --------
    >>> from kalman_vs_infoset.api import load_scenario
    >>> sc = load_scenario("kp_fig5", experiment={"runs": 4}, model={"nu_mps2": 0.01})
    >>> sc.experiment.runs, sc.model.nu_mps2
    (4, 0.01)
    >>> sc.name
    'kp_fig5+experiment.runs=4+model.nu_mps2=0.01'
    """
    if not isinstance(name_or_path, str | Path):  # None raised os.fspath's TypeError
        raise TypeError(f"name_or_path must be a scenario's name or path, got {name_or_path!r}")
    return _scenario.load_scenario(
        name_or_path, overrides_as_sets(overrides), via="keyword overrides"
    )


def _resolve(scenario: InterceptScenario | str | Path) -> InterceptScenario:
    return scenario if isinstance(scenario, InterceptScenario) else load_scenario(scenario)


def _choice(sc: InterceptScenario, estimator: str | None, noise: str | None):
    """The estimator and noise names (the scenario's by default), checked before any
    run: an unknown name is a ``ValueError`` naming the allowed ones, as the command
    line refuses it, not a table of failed runs."""
    for what, name in (("estimator", estimator), ("noise", noise)):
        if name is not None and not isinstance(name, str):  # e.g. a list of names
            raise TypeError(f"{what} must be one name (a str), got {name!r}")
        # an empty name ran the scenario's default under no word (None asks for it)
        if name is not None and not name.strip():
            raise ValueError(f"{what} must name one (None: the scenario's), got {name!r}")
    estimator = estimator or sc.experiment.estimator
    _intercept.registration(estimator)  # the engagement's own checks, before any run
    return estimator, _intercept.check_noise(noise or sc.experiment.noise)


def run_engagement(
    scenario: InterceptScenario | str | Path,
    estimator: str | None = None,
    noise: str | None = None,
    *,
    run: int = 0,
    seed: int | None = None,
) -> EngagementResult:
    """One engagement: run ``run`` of the Monte Carlo with root seed ``seed``.

    The realisation (truth and noise) is the command line's run ``run``: ``kvi intercept
    SCENARIO --seed seed`` writes the same numbers in its row ``run``, to the last digit.

    Parameters
    ----------
    scenario : InterceptScenario, str or pathlib.Path
        A scenario (:func:`load_scenario`), or a bundled name or file path.
    estimator : str, optional
        A registered intercept estimator (:func:`estimators`); default: the scenario's.
    noise : str, optional
        One of :data:`NOISES`; default: the scenario's.
    run : int, default 0
        The run index ``j``: the seed is ``SeedSequence(seed, spawn_key=(j,))``.
    seed : int, optional
        The root seed; default: the scenario's ``experiment.seed``.

    Returns
    -------
    EngagementResult
        Miss, fuel, checks; ``.as_row()`` is the results table's row.

    Examples
    --------
    >>> from kalman_vs_infoset.api import load_scenario, run_engagement
    >>> sc = load_scenario("kp_fig3")
    >>> a = run_engagement(sc, "infoset", "random", run=0)
    >>> b = run_engagement(sc, "ukf", "random", run=0)   # the same truth and noise
    >>> a.truth0 == b.truth0 and a.truth_outside == 0
    True
    """
    sc = _resolve(scenario)
    estimator, noise = _choice(sc, estimator, noise)
    run = integer_in(run, "run", 0, runner.MAX_RUNS - 1)  # the last index a command runs
    seed = root_seed(seed, sc.experiment.seed)
    rng = np.random.default_rng(runner.run_seed(seed, run))
    return _intercept.run_engagement(sc, estimator, noise, rng)


def run_experiment(
    scenario: InterceptScenario | str | Path,
    estimator: str | None = None,
    noise: str | None = None,
    *,
    runs: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
    workers: int | None = 1,
    scheduler: str | None = None,
    executor: Executor | None = None,
    progress: bool = False,
    rerun_other_code: bool = False,
) -> pd.DataFrame:
    """A Monte Carlo of the intercept: one row per run (``docs/results.md``).

    Parameters
    ----------
    scenario : InterceptScenario, str or pathlib.Path
        A scenario, or a bundled name or file path.
    estimator, noise : str, optional
        Default: the scenario's.
    runs : int, optional
        Runs ``0 .. runs-1``; default: the scenario's ``experiment.runs``.
    seed : int, optional
        Root seed; default: the scenario's.
    out : str or pathlib.Path, optional
        A results folder: the runs are written (and resumed) there exactly as by
        ``kvi intercept --out``. ``None`` (default): computed in memory, nothing written.
    workers : int, optional
        Local worker processes (default 1: in this process; ``None``: the CPUs this
        process may run on, its affinity mask on Linux).
    scheduler : str, optional
        A Dask scheduler's address (``pip install 'kalman-vs-infoset[cluster]'``).
    executor : concurrent.futures.Executor, optional
        An executor of one's own for the runs' chunks.
    progress : bool, default False
        A progress bar (``tqdm.auto``: terminal or notebook).
    rerun_other_code : bool, default False
        With ``out``: run again the runs of a table there that other code wrote,
        replacing it (``kvi intercept --rerun-other-code``); by default such a table is
        refused (``InputError``), while the runs of this code are always resumed.

    Returns
    -------
    pandas.DataFrame
        One row per run, sorted by ``run``; a failed run has ``status == "failed"`` and
        its ``error``, and NaN in the result columns (which are there even when every
        run failed).

    Raises
    ------
    kalman_vs_infoset.experiments.errors.InputError
        A plug-in estimator that cannot be built on the scenario's channels (built once
        before any run, as the commands do), or a results table in ``out`` that cannot
        be resumed.

    Examples
    --------
    >>> from kalman_vs_infoset.api import run_experiment
    >>> df = run_experiment("kp_fig3", "ekf", "random", runs=2)
    >>> list(df["run"]), bool((df["status"] == "ok").all())
    ([0, 1], True)
    """
    sc = _resolve(scenario)
    estimator, noise = _choice(sc, estimator, noise)
    runs = sc.experiment.runs if runs is None else integer_in(runs, "runs", 1)
    workers = None if workers is None else integer_in(workers, "workers", 1)  # 0 meant all CPUs
    seed = root_seed(seed, sc.experiment.seed)
    if executor is not None and not isinstance(executor, Executor):
        raise TypeError(f"executor must be a concurrent.futures.Executor, got {executor!r}")
    if out is not None and not isinstance(out, str | Path):
        raise TypeError(f"out must be a folder's path (str or pathlib.Path), got {out!r}")
    if out is not None and not str(out).strip():  # the command line refuses --out ''
        raise ValueError("out must name a folder (None: computed in memory)")
    if scheduler is not None and not (isinstance(scheduler, str) and scheduler.strip()):
        # an empty address ran the runs locally without a word
        raise ValueError(f"scheduler must be a Dask scheduler's address, got {scheduler!r}")
    # a plug-in that cannot be built: one InputError here, as the commands say it in one
    # line, not a failed row per run
    intercept_runs.check_plug_ins(sc, [estimator])
    if out is not None:
        df = intercept_runs.run_experiment(
            sc, estimator, noise, runs, seed, Path(out), workers, scheduler, progress, executor,
            rerun_other_code=bool(rerun_other_code),
        )  # fmt: skip
        return with_columns(df, EngagementResult.columns())
    job = intercept_runs.intercept_job(sc, estimator, noise, seed)
    chunks = runner.results(job, list(range(runs)), executor, workers, scheduler)
    bar = progress_bar(runs, 0, job.desc, progress)
    rows = []
    try:
        for pairs in chunks:
            rows += [{**job.base, "run": j, **row} for j, row in pairs]
            bar.update(len(pairs))
    finally:
        bar.close()
    df = pd.DataFrame(rows).sort_values("run").reset_index(drop=True)
    runner.report_failures(job, df)
    return with_columns(df, EngagementResult.columns())


def trace(
    scenario: InterceptScenario | str | Path,
    estimator: str | None = None,
    noise: str | None = None,
    *,
    runs: Sequence[int] = (0,),
    seed: int | None = None,
    sets_every: int = 10,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The step-by-step history of runs: what ``--trace`` writes, as DataFrames.

    Parameters
    ----------
    scenario, estimator, noise, seed
        As for :func:`run_engagement`.
    runs : sequence of int, default (0,)
        The runs to replay with every step recorded.
    sets_every : int, default 10
        Record the belief's set (polygon estimators) every this many steps.

    Returns
    -------
    steps : pandas.DataFrame
        One row per (run, step, channel): truth, estimate, forecast-miss interval,
        control (``docs/results.md``).
    sets : pandas.DataFrame
        One row per vertex of the recorded sets (empty for the Kalman filters).

    Raises
    ------
    Exception
        Whatever the estimator raises: a replay is for looking at a run, so its error
        comes with its traceback (:func:`run_experiment` records it in the run's row,
        status ``failed``, and goes on).

    Examples
    --------
    >>> from kalman_vs_infoset.api import trace
    >>> steps, sets = trace("kp_fig3", "ekf", "random")
    >>> int(steps["run"].max()), len(sets)
    (0, 0)
    """
    sc = _resolve(scenario)
    estimator, noise = _choice(sc, estimator, noise)
    seed = root_seed(seed, sc.experiment.seed)
    if isinstance(runs, str) or not isinstance(runs, Sequence | np.ndarray):
        raise TypeError(f"runs must be a sequence of run indices (e.g. [0, 3]), got {runs!r}")
    runs = [integer_in(j, "a run index", 0, runner.MAX_RUNS - 1) for j in runs]
    if not runs:  # (two frames without columns came back)
        raise ValueError("runs must name at least one run to trace")
    if len(set(runs)) < len(runs):  # each step came back twice
        raise ValueError(f"runs must be distinct, got {runs}")
    sets_every = integer_in(sets_every, "sets_every", 1)
    steps, sets, _ = _traces.intercept_trace(sc, estimator, noise, seed, runs, sets_every)
    return steps, sets


def estimators(problem: str = "intercept") -> tuple[str, ...]:
    """The registered estimators of a problem (``"intercept"`` or ``"attitude"``).

    Examples
    --------
    >>> from kalman_vs_infoset.api import estimators
    >>> {"infoset", "ekf", "ukf"} <= set(estimators())
    True
    """
    if problem not in registry.PROBLEMS:
        raise ValueError(f"problem must be one of {registry.PROBLEMS}, got {problem!r}")
    return registry.names(problem)


def get_estimator(name: str, problem: str = "intercept") -> Registration:
    """A registered estimator: its options model, factory and one-line doc.

    Examples
    --------
    >>> from kalman_vs_infoset.api import get_estimator
    >>> get_estimator("ukf").options.model_fields["n_sigma"].default
    3.0
    """
    if name in registry.PROBLEMS and problem not in registry.PROBLEMS:
        raise ValueError(
            f"get_estimator takes (name, problem): got name {name!r} and problem {problem!r} "
            f"(registry.get takes (problem, name))"
        )
    return registry.get(problem, name)


#: :func:`kalman_vs_infoset.estim.registry.register`: add an estimator (a plug-in)
register_estimator = registry.register
