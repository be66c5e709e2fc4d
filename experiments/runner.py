"""Monte Carlo runner: tasks on an Executor, paired seeding, atomic resumable Parquet.

One runner for every problem: it knows none. A problem hands it a :class:`Job` whose
``task`` runs a chunk of run indices (the intercept's in :mod:`experiments.intercept_runs`,
the attitude loops' in :mod:`experiments.cmd_attitude`).

* Tasks: chunks of run indices (one run per task for the intercept, larger chunks for
  the vectorised attitude loops), fixed by the indices, not by the worker count.
* Seeding: run ``j`` uses ``SeedSequence(seed).spawn(runs)[j]``; the realisation
  depends only on (scenario, seed, j), never on the worker count or the order,
  and is the same for every estimator (paired comparison).
* Executor: runs in this process for one worker, a ``ProcessPoolExecutor`` for
  several (its workers exit when the command dies), or a Dask cluster's
  ``Client.get_executor()`` with ``scheduler`` (same results either way).
* Results: one Parquet file per (scenario, choices, seed) with one row per run, the
  resolved scenario and the code's identity in its Parquet metadata and as JSON in
  ``<out>/_meta/`` (:mod:`experiments.results`); both written atomically (temporary file +
  ``os.replace``). Rerunning the same command completes only the missing runs, and
  finished runs are never deleted; a failing run is recorded with its run id and error,
  reported on stderr, and does not stop the others. The JSON also records which code
  wrote the runs (:mod:`experiments.provenance`); a file written by another scenario or
  other sources is refused, not extended, and so is a file that is not a results table.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
from kalman_vs_infoset.experiments.errors import InputError, check_stop, runs_text
from kalman_vs_infoset.experiments.executors import (  # noqa: F401 - re-exported
    WorkerLost,
    executor_or,
    make_executor,
    results,
)
from kalman_vs_infoset.experiments.files import atomic_write, exclusive
from kalman_vs_infoset.experiments.limits import RunLimits, reraise_timeout
from kalman_vs_infoset.experiments.options import MAX_RUNS, MAX_SEED  # with the parser's bounds
from kalman_vs_infoset.experiments.progress import progress_bar, steps_shown
from kalman_vs_infoset.experiments.provenance import code_identity, estimator_identity
from kalman_vs_infoset.experiments.results import (
    check_columns,
    existing_sidecar,
    read_metadata,
    sidecar_path,
    write_table,
)

SAVE_EVERY_S = 2.0


def run_seed(seed: int, j: int) -> np.random.SeedSequence:
    """The seed of run ``j``: ``SeedSequence(seed).spawn(n)[j]`` for any ``n > j``."""
    return np.random.SeedSequence(seed, spawn_key=(j,))


@dataclass(frozen=True)
class Job:
    """One results file: a scenario's runs with one estimator and one noise.

    ``task(runs)`` (picklable: it runs on worker processes) simulates a chunk of run
    indices and returns ``(run, row)`` pairs, one per index, a failed run as a row with
    ``status = "failed"`` and its ``error``. Chunks are ``chunk`` consecutive indices
    (``j // chunk`` groups), whatever the worker count, so the results do not depend on
    it. ``meta`` (the resolved scenario and choices) is written beside the table and
    compared on resume; ``base`` holds the columns of every row.
    """

    name: str
    label: str
    seed: int
    meta: dict[str, Any]
    base: dict[str, Any]
    task: Callable[[list[int]], list[tuple[int, dict[str, Any]]]]
    chunk: int = 1
    #: the estimator's problem ("intercept", "attitude"): a plug-in's code is recorded
    #: and checked on resume (:func:`experiments.provenance.estimator_identity`)
    problem: str | None = None
    #: ``decides(description) -> description``: the part of a results description (as
    #: JSON) that decides this job's runs, where it is less than the whole (the tables
    #: of options its runs never read left out); compared on resume, both sides alike
    decides: Callable[[dict[str, Any]], dict[str, Any]] | None = None
    #: other registered estimators whose code decides the runs (the game adversary's
    #: information set): a plug-in among them is recorded and checked as the job's own
    reads: frozenset[str] = frozenset()
    #: columns of text a row holds besides ``status``, ``error`` and the text of
    #: ``base`` (a resumed table rewritten by another tool is checked against them)
    text: frozenset[str] = frozenset()

    @property
    def desc(self) -> str:
        return f"{self.name} {self.label}"


def job_path(out_dir: Path, job: Job) -> Path:
    return Path(out_dir) / f"{job.name}-{job.label}-s{job.seed}.parquet"


def is_integer(value: Any) -> bool:
    """Whether ``value`` is an integer: Python or numpy, not a bool, not a float (which
    ``int()`` would truncate: seed 1.5 was run as seed 1)."""
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


def _whole(value: Any, flag: str, lo: int, hi: int) -> int:
    """``value`` if it is an integer (:func:`is_integer`) in ``[lo, hi]``; else InputError."""
    if not (is_integer(value) and lo <= value <= hi):
        raise InputError(f"{flag} {value!r}: must be an integer in [{lo}, {hi}]")
    return int(value)


def check_seed(seed: int) -> int:
    return _whole(seed, "--seed", 0, MAX_SEED)


def check_runs(runs: int) -> int:
    return _whole(runs, "--runs", 1, MAX_RUNS)


def _write_rows(path: Path, rows: list[dict[str, Any]], meta: dict[str, Any]) -> None:
    df = _typed(pd.DataFrame(rows), rows).sort_values("run").reset_index(drop=True)
    try:
        write_table(path, df, meta)  # the description travels in the Parquet metadata too
    except (pa.ArrowTypeError, pa.ArrowInvalid) as exc:
        # previous rows of other types than the new ones (a table changed by another
        # tool that check_columns could not tell): one line; the table stays as it was
        said = str(exc.args[0] if exc.args else exc).splitlines()[0]
        raise InputError(
            f"{path}: the new runs cannot be saved beside its previous rows ({said}); "
            "delete it to compute its runs again"
        ) from None


def _typed(df: pd.DataFrame, rows: list[dict[str, Any]]) -> pd.DataFrame:
    """Integer and boolean columns with gaps (a failed run has no results) as nullable
    integers and booleans, not floats and objects: once the failed runs are run again,
    the table has the dtypes of a table that never had a failure."""
    for col in df.columns[df.isna().any()]:
        values = [r.get(col) for r in rows]
        given = [v for v in values if v is not None and not pd.isna(v)]
        if not given:
            continue
        if all(isinstance(v, bool | np.bool_) for v in given):
            dtype = "boolean"
        elif all(isinstance(v, int | np.integer) and not isinstance(v, bool) for v in given):
            dtype = "Int64"
        else:
            continue
        df[col] = pd.array([None if v is None or pd.isna(v) else v for v in values], dtype)
    return df


def _read_table(path: Path, job: Job) -> dict[int, dict[str, Any]]:
    """The rows of a results table by run, or one line naming the file and the remedy."""
    try:
        df = pd.read_parquet(path)
    except Exception as exc:  # truncated, or not Parquet at all
        raise InputError(
            f"{path}: cannot read previous results ({type(exc).__name__}); delete {path} "
            "to compute its runs again"
        ) from None
    # changed since written: one line, not a traceback later
    words = {k for k, v in job.base.items() if isinstance(v, str)} | {"status", "error"}
    check_columns(path, frozenset(words) | job.text)
    if not {"run", "status"} <= set(df.columns):
        raise InputError(
            f"{path}: not a results table (no 'run' and 'status' columns); use another "
            f"--out or delete {path}"
        )
    run = df["run"]
    if not pd.api.types.is_integer_dtype(run) or (run < 0).any() or run.duplicated().any():
        raise InputError(
            f"{path}: not a results table (column 'run' does not hold distinct run "
            f"indices); use another --out or delete {path}"
        )
    return {int(r["run"]): r for r in df.to_dict("records")}


def batched_task(simulate, seed: int, runs: list[int]) -> list[tuple[int, dict[str, Any]]]:
    """A chunk of a vectorised loop: ``simulate(seeds)`` returns one row per seed; when
    the batch raises, each run is retried alone, so a failing run is recorded with its
    own run id and error and the others keep theirs."""
    t0 = time.perf_counter()
    try:
        rows = simulate([run_seed(seed, j) for j in runs])
    except MemoryError:
        raise  # a resource, not the run: not recorded (the runner says so)
    except Exception as exc:
        reraise_timeout(exc)  # a CPU limit's timeout is the limit's to report
        if len(runs) > 1:
            return [pair for j in runs for pair in batched_task(simulate, seed, [j])]
        failed = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
        return [(runs[0], {**failed, "wall_s": time.perf_counter() - t0})]
    wall = (time.perf_counter() - t0) / len(runs)
    ok = {"status": "ok", "error": "", "wall_s": wall}
    return [(j, {**r, **ok}) for j, r in zip(runs, rows, strict=True)]


def run_job(
    job: Job,
    runs: int,
    out_dir: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    executor: Executor | None = None,
    limits: RunLimits | None = None,
    rerun_other_code: bool = False,
) -> pd.DataFrame:
    """Run (or complete) runs ``0..runs-1`` of ``job``; return their rows, by run.

    Finished runs are kept on disk whatever ``runs`` is (a smaller ``runs`` only
    reports fewer); failed runs are run again; a file of another scenario is refused
    (one line), and so is one of other sources unless ``rerun_other_code`` (its runs
    are then run again and the file replaced: it is deleted before the first run).
    Complete results are only read (a read-only folder can be summarised again);
    otherwise the table is written by one command at a time
    (:func:`experiments.files.exclusive`). ``limits`` are a run's CPU-time and memory
    limits (:mod:`experiments.limits`).
    """
    check_seed(job.seed)
    check_runs(runs)
    path = job_path(out_dir, job)
    meta = {**job.meta, "code": _code(job)}
    meta_path = sidecar_path(path)
    if path.exists() and not _check_resumable(
        path, existing_sidecar(path), meta, rerun_other_code, job.decides
    ):
        table = _read_table(path, job)
        if all(table.get(j, {}).get("status") == "ok" for j in range(runs)):
            _say_all_done(job, runs, path)  # the output is otherwise the same
            return _reported(job, path, table, runs)
    made = [d for d in (path.parent, *path.parent.parents) if not d.exists()]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--out {out_dir}: cannot create the folder ({exc.strerror})") from None
    wrote_meta = False  # a description this command wrote where there was none
    made += [] if meta_path.parent.exists() else [meta_path.parent]
    try:
        with exclusive(path, job.desc):
            table = {}
            if path.exists():  # read again: another command may have written it meanwhile
                if _check_resumable(
                    path, existing_sidecar(path), meta, rerun_other_code, job.decides
                ):
                    # gone before the new description is written: an interruption
                    # cannot leave the old runs under this code's name
                    path.unlink()
                    print(f"{job.desc}: {path.name} was written by other code: its runs "
                          "are run again", file=sys.stderr)  # fmt: skip
                else:
                    table = _read_table(path, job)
            if not meta_path.exists() or _read_json(meta_path) != meta:
                wrote_meta = not meta_path.exists()
                text = json.dumps(meta, indent=2)
                atomic_write(meta_path, lambda tmp: Path(tmp).write_text(text))
            todo = [j for j in range(runs) if table.get(j, {}).get("status") != "ok"]
            retried = sum(j in table for j in todo)
            kept = runs - len(todo)
            if kept and not todo:  # another command finished them while this one waited
                _say_all_done(job, runs, path)
            elif kept:
                print(f"{job.desc}: {runs_text(kept)} of {runs} already in {path}: running "
                      f"the other {len(todo)}", file=sys.stderr)  # fmt: skip
            if retried:
                print(f"{job.desc}: running {retried} failed runs again", file=sys.stderr)
            if todo:
                _complete(job, runs, todo, table, path, meta, progress,
                          executor, workers, scheduler, limits)  # fmt: skip
    except BaseException:
        if not path.exists():  # refused or stopped before any run finished: no leftovers
            if wrote_meta:
                meta_path.unlink(missing_ok=True)
            for d in sorted(made, key=lambda d: -len(d.parts)):  # deepest first
                try:
                    d.rmdir()
                except OSError:
                    pass
        raise
    return _reported(job, path, table, runs)


def _complete(job, runs, todo, table, path, meta, progress, executor, workers, scheduler,
              limits):  # fmt: skip
    """Run ``todo`` into ``table``, saving it every :data:`SAVE_EVERY_S` and at the end,
    also on Ctrl-C or SIGTERM (finished runs are kept)."""
    bar = progress_bar(runs, runs - len(todo), job.desc, progress)
    last_save = time.monotonic()
    changed = False
    try:
        with steps_shown(progress):  # a slow run in this process shows its steps
            for pairs in results(job, todo, executor, workers, scheduler, limits):
                # one update per chunk: a signal between two bytecodes cannot leave
                # part of a chunk in the table (a vectorised chunk is saved whole)
                table.update({j: {**job.base, "run": j, **row} for j, row in pairs})
                changed = True
                bar.update(len(pairs))
                check_stop()
                if time.monotonic() - last_save > SAVE_EVERY_S:
                    _write_rows(path, list(table.values()), meta)
                    last_save, changed = time.monotonic(), False
    finally:
        bar.close()
        if changed:
            _write_rows(path, list(table.values()), meta)


def _reported(job: Job, path: Path, table: dict[int, dict], runs: int) -> pd.DataFrame:
    """Runs ``0..runs-1`` of ``table`` as a frame; their failures said on stderr and
    counted for the command's last line (:func:`failed_runs`)."""
    df = pd.DataFrame([r for j, r in table.items() if j < runs])
    if len(df):
        df = df.sort_values("run").reset_index(drop=True)
    report_failures(job, df)
    _FAILED[str(path)] = int((df["status"] != "ok").sum()) if len(df) else 0
    return df


#: failed runs of the tables this process reported, by table (the command's last line)
_FAILED: dict[str, int] = {}


def failed_runs() -> int:
    """Failed runs among those the tables reported since :func:`forget_failures`."""
    return sum(_FAILED.values())


def forget_failures() -> None:
    _FAILED.clear()


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _say_all_done(job: Job, runs: int, path: Path) -> None:
    """A resume with nothing left to run says so, in one line on stderr."""
    print(f"{job.desc}: all {runs_text(runs)} already in {path}: none run", file=sys.stderr)


def _code(job: Job) -> dict[str, Any]:
    """The code that writes a job's results: the package's, a plug-in estimator's, and
    those of the plug-ins among the other estimators its runs read (``estimators_read``,
    by name; absent when there are none, as in every description written before it)."""
    code: dict[str, Any] = dict(code_identity())
    plugin = estimator_identity(job.problem, job.meta["estimator"]) if job.problem else None
    if plugin is not None:
        code["estimator"] = plugin
    if job.problem:
        read = {n: estimator_identity(job.problem, n) for n in sorted(job.reads)}
        read = {n: i for n, i in read.items() if i is not None}
        if read:
            code["estimators_read"] = read
    return code


def _check_resumable(
    path: Path,
    meta_path: Path,
    meta: dict[str, Any],
    rerun_other_code: bool = False,
    decides: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
) -> bool:
    """Refuse (one line) to add runs to results of another scenario or other code. The
    resolved scenarios are compared, not the paths that named them, and of them what
    decides a run (:func:`_what_decides_a_run`, then the job's ``decides``). Returns
    whether the file is of other code and ``rerun_other_code`` lets its runs be run
    again."""
    # both descriptions must allow it: the JSON in _meta/ and the table's own, which
    # travels with its rows (a table copied without its JSON beside another job's was
    # resumed under that job's description). A table of an earlier release has only the
    # JSON; a lost or damaged JSON need not cost the runs when the table has its own.
    try:
        descriptions = [own] if (own := read_metadata(path)) else []
    except InputError:  # an unreadable table: _read_table names it and the remedy
        descriptions = []
    try:
        descriptions.append(json.loads(meta_path.read_text()))
    except (OSError, ValueError):
        if not descriptions:
            raise InputError(
                f"{path}: no readable {meta_path.name} to check it against; use another "
                "--out or delete the file"
            ) from None
    other = False
    for old in descriptions:  # each checked: a refusal raises
        other = _other_code(path, meta_path, old, meta, rerun_other_code, decides) or other
    return other


def _other_code(
    path: Path,
    meta_path: Path,
    old: Any,
    meta: dict[str, Any],
    rerun_other_code: bool,
    decides: Callable[[dict[str, Any]], dict[str, Any]] | None,
) -> bool:
    """:func:`_check_resumable` against one stored description ``old``."""
    fix = "use another --out or delete the file"
    if not isinstance(old, dict):
        raise InputError(f"{path}: {meta_path.name} is not a results description; {fix}")
    now = json.loads(json.dumps(meta))  # as the file holds it (JSON types)
    here, there = _what_decides_a_run(now), _what_decides_a_run(old)
    if decides is not None:
        here, there = decides(here), decides(there)
    if there != here:
        key, a, b = _first_difference(there, here)
        raise InputError(
            f"{path}: results of a different scenario ({key}: {a!r} in the file, {b!r} now); {fix}"
        )
    before = (old.get("code") or {}).get("sources_sha256")
    plugin_then = (old.get("code") or {}).get("estimator")
    plugin_now = now["code"].get("estimator")
    read_then = (old.get("code") or {}).get("estimators_read") or {}
    read_now = now["code"].get("estimators_read") or {}
    same_sources = before == meta["code"]["sources_sha256"]
    if same_sources and plugin_then == plugin_now and read_then == read_now:
        return False
    if rerun_other_code:
        return True
    # the command line's flag, and the keyword of the Python front door's run_experiment
    again = f"{fix}, or run them again with --rerun-other-code (Python: rerun_other_code=True)"
    if same_sources and plugin_then != plugin_now:  # the plug-in's code changed
        raise InputError(
            f"{path}: results written by another version of the estimator "
            f"{meta.get('estimator')!r} ({_plugin_text(plugin_then)}, now "
            f"{_plugin_text(plugin_now)}); {again}"
        )
    if same_sources:  # the code of an estimator the runs read changed
        name = next(n for n in sorted({*read_then, *read_now})
                    if read_then.get(n) != read_now.get(n))  # fmt: skip
        raise InputError(
            f"{path}: results written with another version of the estimator {name!r} that "
            f"the runs read ({_plugin_text(read_then.get(name))}, now "
            f"{_plugin_text(read_now.get(name))}); {again}"
        )
    was = f"sources {before[:12]}" if before else "code that recorded no identity"
    raise InputError(
        f"{path}: results written by other code ({was}, now "
        f"{meta['code']['sources_sha256'][:12]}); {again}"
    )


#: scenario fields that decide which runs to make, not what a run gives: the intercept
#: scenario's [experiment] table (runs, seed, estimator and noise; the table's own seed,
#: estimator and noise are in its name and description) and the description text. A
#: study extended through the file (runs = 50 -> 1000) resumes as with --runs.
NOT_A_RUNS_CONDITION = ("experiment", "description")


def _what_decides_a_run(meta: dict[str, Any]) -> dict[str, Any]:
    """A results description without its code and the scenario fields that do not
    change a run (:data:`NOT_A_RUNS_CONDITION`): what a resume must find the same."""
    out = {k: v for k, v in meta.items() if k != "code"}
    if isinstance(out.get("scenario"), dict):
        scenario = out["scenario"]
        out["scenario"] = {k: v for k, v in scenario.items() if k not in NOT_A_RUNS_CONDITION}
    return out


def _plugin_text(identity: dict | None) -> str:
    if not identity:
        return "the package's own"
    sha = identity.get("sources_sha256")
    versions = ", ".join(f"{d} {v}" for d, v in identity.get("distributions", {}).items())
    return f"sources {sha[:12] if sha else 'unknown'}" + (f", {versions}" if versions else "")


def _first_difference(a: Any, b: Any, key: str = "") -> tuple[str, Any, Any]:
    """The first dotted key where two JSON values differ, with both values."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k, _MISSING) != b.get(k, _MISSING):
                return _first_difference(a.get(k, _MISSING), b.get(k, _MISSING), f"{key}.{k}")
    return key.lstrip(".") or "(all)", a, b


class _Missing:
    def __repr__(self) -> str:
        return "(not set)"


_MISSING = _Missing()


def report_failures(job: Job, df: pd.DataFrame, shown: int = 3) -> None:
    """A failed run always says why (stderr, one line each; the rows keep the error)."""
    if not len(df) or "status" not in df:
        return
    failed = df[df["status"] != "ok"]
    for _, r in failed.head(shown).iterrows():
        print(f"{job.desc}: run {int(r['run'])} failed: {r.get('error', '')}", file=sys.stderr)
    if len(failed) > shown:
        print(f"{job.desc}: {len(failed) - shown} more runs failed", file=sys.stderr)
