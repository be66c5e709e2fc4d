"""The Python front door's argument checks, shared by :mod:`kalman_vs_infoset.api` and
:mod:`kalman_vs_infoset.api_attitude` (each names the argument, as a Python caller
wrote it, not the command line's flag), and the shape of the tables both return."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from kalman_vs_infoset.experiments import runner
from kalman_vs_infoset.experiments import scenario as _scenario

if TYPE_CHECKING:
    import pandas as pd


def with_columns(df: pd.DataFrame, columns: Iterable[str]) -> pd.DataFrame:
    """``df`` with every column of ``columns`` (NaN where no run gave one): a table whose
    runs all failed holds only ``status`` and ``error``, and selecting a result column
    raised KeyError."""
    missing = [c for c in columns if c not in df.columns]
    return df.reindex(columns=[*df.columns, *missing]) if missing else df


def overrides_as_sets(tables: Any) -> list[str]:
    """Keyword tables of overrides as ``--set`` items (``TABLE.KEY=<TOML value>``); a
    value a scenario file cannot hold (``None``, a path, an object) is a ``TypeError``
    naming its key (``None`` was refused as the command line's ``'null'``)."""
    items = _scenario.dotted_fields(tables)
    for key, value in items.items():
        if not _toml_like(value):
            raise TypeError(
                f"{key}={value!r}: a scenario value is a number, a bool, a str or a list of them"
            )
    return [f"{key}={_scenario.toml_value(v)}" for key, v in items.items()]


def _toml_like(value: Any) -> bool:
    """Whether ``value`` is what a scenario file holds: numbers, booleans, strings and
    lists of them (numpy scalars and arrays as their lists, a tuple as a list)."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, list | tuple):
        return all(_toml_like(v) for v in value)
    return isinstance(value, bool | int | float | str)


def integer_in(value: Any, name: str, least: int, most: int = runner.MAX_RUNS) -> int:
    """An integer argument (:func:`runner.is_integer`) in ``[least, most]``: by default at
    most the command line's run count (a count of ``2**40`` ran for hours without a word,
    or failed in a bare ``MemoryError``)."""
    if not runner.is_integer(value):
        raise TypeError(f"{name} must be an integer, got {value!r}")
    if value < least:
        raise ValueError(f"{name} must be at least {least}, got {value}")
    if value > most:
        raise ValueError(f"{name} must be at most {most}, got {value}")
    return int(value)


def root_seed(value: Any, scenario_seed: int) -> int:
    """The root seed: the scenario's when ``None``, else an integer in ``[0, MAX_SEED]``
    (the results tables hold it as int64)."""
    if value is None:
        return scenario_seed
    return integer_in(value, "seed", 0, runner.MAX_SEED)
