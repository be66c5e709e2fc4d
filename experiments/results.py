"""Results folders that describe themselves.

A results table (one Parquet file per scenario, choices and seed; one row per run) holds
in its key-value metadata, under :data:`METADATA_KEY`, the JSON of the resolved scenario,
the choices, the seed and the identity of the code that wrote it (package version, git
commit of the package's own sources, SHA-256 of the sources). The same JSON is kept in
``<folder>/_meta/<table>.json``, where a resumed run checks it, and the traces of
``--trace`` in ``<folder>/_traces/``: folders whose names start with ``_`` are skipped
by Parquet readers, so ``pandas.read_parquet(folder)`` reads every run of a folder of
intercept results in one call. :func:`load_results` does so for any results folder
(figures and tables beside the runs are skipped), with each table's metadata.

The columns are described in ``docs/results.md``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.files import atomic_write, derived_write

#: the key of the results' description in a table's Parquet key-value metadata
METADATA_KEY = b"kalman_vs_infoset"
#: subfolders of a results folder: descriptions (JSON) and traces
META_DIR, TRACE_DIR = "_meta", "_traces"
#: file-name endings of traces (not results tables)
TRACE_SUFFIXES = ("-trace.parquet", "-trace-sets.parquet")
#: the Parquet key marking a command's combined table (compare, fig5, adversaries: the
#: rows of the runs' own tables, gathered; :func:`report.write_tables`)
COMBINED_KEY = b"kalman_vs_infoset_combined"
#: the Parquet key of the columns and their types as written (:func:`check_columns`)
COLUMNS_KEY = b"kalman_vs_infoset_columns"


def sidecar_path(table: Path) -> Path:
    """``<folder>/_meta/<stem>.json``: the description of the table ``table``."""
    table = Path(table)
    return table.parent / META_DIR / f"{table.stem}.json"


def existing_sidecar(table: Path) -> Path:
    """The description to check a table against: in ``_meta/``, or (results written by
    earlier releases) beside the table."""
    new = sidecar_path(table)
    old = Path(table).with_suffix(".json")
    return old if not new.exists() and old.exists() else new


def write_table(
    path: Path, df: pd.DataFrame, meta: dict[str, Any] | None, combined: bool = False
) -> None:
    """Write ``df`` to ``path`` atomically with ``meta`` (if any) as JSON in its metadata,
    marked as a command's combined table if ``combined`` (:data:`COMBINED_KEY`)."""
    table = pa.Table.from_pandas(df, preserve_index=False)
    kv = dict(table.schema.metadata or {})
    kv[COLUMNS_KEY] = json.dumps(_columns(table.schema)).encode()
    if meta is not None:
        kv[METADATA_KEY] = json.dumps(meta, default=str).encode()
    if combined:
        kv[COMBINED_KEY] = b"1"
    table = table.replace_schema_metadata(kv)
    # a combined table is derived from the runs' tables: not written in a read-only folder
    writer = derived_write if combined else atomic_write
    writer(Path(path), lambda tmp: pq.write_table(table, tmp))


def _columns(schema: pa.Schema) -> list[list[str]]:
    return [[f.name, str(f.type)] for f in schema]


def check_columns(path: Path, text: frozenset[str] = frozenset()) -> None:
    """Refuse (one line) a table whose columns are not those it was written with: a
    file changed by another tool since the package wrote it (a number column turned to
    text ended a resume in a traceback: the summary could not convert it, or the save
    could not put it beside the new runs' numbers). A table without the record (an
    earlier release's, or one rewritten by pandas, which drops it) is checked for the
    same edit by the columns the package writes as text, ``text``: any other column of
    text is refused."""
    schema = pq.read_schema(path)
    recorded = (schema.metadata or {}).get(COLUMNS_KEY)
    if recorded is None:
        _check_text_columns(path, schema, text)
        return
    try:
        written = {name: kind for name, kind in json.loads(recorded)}
    except (ValueError, TypeError):
        written = {}
    now = dict(_columns(schema))
    for name in sorted(written.keys() | now.keys()):
        if written.get(name) != now.get(name):
            was, is_ = written.get(name, "none"), now.get(name, "none")
            raise InputError(
                f"{path}: its columns are not those this package wrote (column {name!r}: "
                f"{was} written, {is_} now; the file was changed since); delete it to "
                "compute its runs again"
            )


def _check_text_columns(path: Path, schema: pa.Schema, text: frozenset[str]) -> None:
    """:func:`check_columns` of a table without its columns' record: text only in the
    columns ``text``."""
    for f in schema:
        if f.name not in text and (pa.types.is_string(f.type) or pa.types.is_large_string(f.type)):
            raise InputError(
                f"{path}: its column {f.name!r} holds text where this package writes "
                "numbers (the file was changed since); delete it to compute its runs again"
            )


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The description a results table carries (scenario, choices, seed, ``code``).

    Parameters
    ----------
    path : str or pathlib.Path
        A results table (``*.parquet``) written by the runner.

    Returns
    -------
    dict
        Empty for a table written by an earlier release (its ``_meta`` JSON, or the
        JSON beside it, holds the same).
    """
    try:
        kv = pq.read_schema(path).metadata or {}
    except (OSError, pa.ArrowInvalid) as exc:
        raise InputError(f"{path}: not a readable Parquet file ({type(exc).__name__})") from None
    raw = kv.get(METADATA_KEY)
    if not raw:
        return {}
    try:
        meta = json.loads(raw)
    except ValueError:  # JSONDecodeError, or bytes that are not UTF-8
        meta = None
    if not isinstance(meta, dict):  # not what this package writes: another tool's edit
        raise InputError(f"{path}: its description ({METADATA_KEY!r} metadata) is damaged")
    return meta


def _combined(path: Path) -> bool:
    """Whether ``path`` is a command's combined table (its rows are the runs' own)."""
    if path.name.endswith("-adversaries.parquet"):  # written before the mark, beside its runs
        return True
    try:
        return COMBINED_KEY in (pq.read_schema(path).metadata or {})
    except (OSError, pa.ArrowInvalid):
        return False  # unreadable: load_results says so when it reads it


def _tables(folder: Path) -> list[Path]:
    """The runs' own tables of a results folder: beside the combined table (intercept,
    adversaries, sweep) and in ``runs/`` (compare, fig5), both when two commands wrote
    to one ``--out`` (their default folders are the same); a combined table alone is
    read as is."""
    found = sorted(p for p in folder.glob("*.parquet") if not p.name.endswith(TRACE_SUFFIXES))
    files = [p for p in found if not _combined(p)]
    if (folder / "runs").is_dir():
        files += _tables(folder / "runs")
    return files or found


def _scenario_of(description: dict[str, Any]) -> Any:
    """What makes two tables of one name the same job: the job and its scenario."""
    return [description.get(k) for k in ("scenario", "estimator", "noise", "controller", "seed")]


def load_results(folder: str | Path) -> pd.DataFrame:
    """Every run of a results folder (or one results table) in one DataFrame.

    Parameters
    ----------
    folder : str or pathlib.Path
        A folder written by ``kvi intercept``, ``kvi attitude``, ``kvi compare``,
        ``kvi fig5`` (their ``runs/``), or :func:`kalman_vs_infoset.api.run_experiment`
        with ``out`` (by several of them: the tables at its top and in its ``runs/``);
        or a single results table.

    Returns
    -------
    pandas.DataFrame
        The rows of every results table (``docs/results.md``); ``df.attrs["metadata"]``
        maps each table's file name to its description (:func:`read_metadata`).

    Examples
    --------
    >>> import tempfile
    >>> from kalman_vs_infoset.api import load_results, run_experiment
    >>> with tempfile.TemporaryDirectory() as out:
    ...     _ = run_experiment("kp_fig3", "ekf", "random", runs=2, out=out)
    ...     df = load_results(out)
    >>> len(df), next(iter(df.attrs["metadata"].values()))["scenario"]["name"]
    (2, 'kp_fig3')
    """
    if not isinstance(folder, str | Path):  # None raised os.fspath's TypeError
        raise TypeError(f"folder must be a results folder's or table's path, got {folder!r}")
    folder = Path(folder)
    if folder.is_file():
        files = [folder]
    elif folder.is_dir():
        files = _tables(folder)
        if not files:  # most likely the wrong folder: an empty table would hide that
            raise InputError(f"{folder}: no results tables (*.parquet) here or in runs/")
    else:
        raise InputError(f"{folder}: no such results folder or table")
    frames: list[pd.DataFrame] = []
    meta: dict[str, dict[str, Any]] = {}
    runs_read: dict[str, set[int]] = {}  # by table name: one job's runs
    for f in files:
        try:
            df = pd.read_parquet(f)
        except Exception as exc:  # truncated or not Parquet
            raise InputError(f"{f}: cannot read ({type(exc).__name__})") from None
        if not {"run", "status"} <= set(df.columns):
            continue  # a summary table beside the runs
        # a table of the same name at the top and in runs/ holds the runs of one job
        # (run j is seeded alike in both) when it describes the same scenario: each run
        # is read once, the top's first; one of another scenario (the file edited
        # between the commands) is read whole, its description under runs/<name>
        described = read_metadata(f)
        key = f.name
        if key in meta and _scenario_of(meta[key]) != _scenario_of(described):
            key = f"{f.parent.name}/{f.name}"
        seen = runs_read.setdefault(key, set())
        df = df[~df["run"].isin(seen)]
        seen.update(int(r) for r in df["run"])
        frames.append(df)
        meta.setdefault(key, described)
    if not frames:  # only summaries (or other tables): as wrong a place as an empty one
        raise InputError(f"{folder}: no results table (one with 'run' and 'status' columns)")
    out = pd.concat(frames, ignore_index=True)
    out.attrs["metadata"] = meta
    return out
