"""Validation rules of the attitude scenarios' tables (the intercept's are typed
pydantic tables, :mod:`experiments.sim.intercept_config`).

Every field is checked: unknown keys, wrong types and out-of-range values raise
:class:`~experiments.errors.InputError` with one line naming the file, the field
and the allowed range. Files are read by :mod:`experiments.scenario` (re-exported).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from experiments.errors import InputError
from experiments.scenario import apply_overrides, load_toml, override_suffix  # noqa: F401


@dataclass(frozen=True)
class Num:
    """A real number in ``[lo, hi]`` (closed unless ``open_lo``/``open_hi``)."""

    lo: float = -math.inf
    hi: float = math.inf
    open_lo: bool = False
    open_hi: bool = False
    integer: bool = False

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a number"
        lb = "(" if self.open_lo else "["
        rb = ")" if self.open_hi else "]"
        return f"{kind} in {lb}{self.lo:g}, {self.hi:g}{rb}"

    def check(self, value: Any) -> float | int:
        ok_type = isinstance(value, int) if self.integer else isinstance(value, int | float)
        if isinstance(value, bool) or not ok_type or not math.isfinite(value):
            raise ValueError(self.describe())
        below = value <= self.lo if self.open_lo else value < self.lo
        above = value >= self.hi if self.open_hi else value > self.hi
        if below or above:
            raise ValueError(self.describe())
        return int(value) if self.integer else float(value)


@dataclass(frozen=True)
class Choice:
    """One string out of a fixed set."""

    options: tuple[str, ...]

    def describe(self) -> str:
        return "one of " + ", ".join(repr(o) for o in self.options)

    def check(self, value: Any) -> str:
        if not isinstance(value, str) or value not in self.options:
            raise ValueError(self.describe())
        return value


@dataclass(frozen=True)
class Bool:
    def describe(self) -> str:
        return "true or false"

    def check(self, value: Any) -> bool:
        if not isinstance(value, bool):
            raise ValueError(self.describe())
        return value


@dataclass(frozen=True)
class Vec:
    """A list of ``length`` numbers, each satisfying ``item`` (any length if None)."""

    item: Num
    length: int | None = None

    def describe(self) -> str:
        n = f"{self.length} " if self.length is not None else ""
        return f"a list of {n}numbers, each {self.item.describe()}"

    def check(self, value: Any) -> tuple[float, ...]:
        if not isinstance(value, list) or (self.length is not None and len(value) != self.length):
            raise ValueError(self.describe())
        try:
            return tuple(self.item.check(v) for v in value)
        except ValueError:
            raise ValueError(self.describe()) from None


@dataclass(frozen=True)
class Interval:
    """A two-element list ``[lo, hi]`` with ``lo <= hi``, each in ``item``'s range."""

    item: Num

    def describe(self) -> str:
        return f"a list [lo, hi] with lo <= hi, each {self.item.describe()}"

    def check(self, value: Any) -> tuple[float, float]:
        vals = Vec(self.item, 2).check(value) if isinstance(value, list) else None
        if vals is None or vals[0] > vals[1]:
            raise ValueError(self.describe())
        return vals[0], vals[1]


@dataclass(frozen=True)
class Str:
    def describe(self) -> str:
        return "a string"

    def check(self, value: Any) -> str:
        if not isinstance(value, str):
            raise ValueError(self.describe())
        return value


Rule = Num | Choice | Bool | Vec | Interval | Str


def validate_table(
    source: str | Path,
    table: Mapping[str, Any],
    rules: Mapping[str, Rule],
    defaults: Mapping[str, Any] | None = None,
    prefix: str = "",
    required: Sequence[str] = (),
) -> dict[str, Any]:
    """Check ``table`` against ``rules``; return the checked values with defaults filled in.

    Raises InputError for unknown keys, missing required keys, wrong types and values
    out of range, with one line ``FILE: field 'PREFIX.KEY' must be ...``.
    """
    defaults = dict(defaults or {})
    if not isinstance(table, Mapping):
        raise InputError(f"{source}: '{prefix.rstrip('.')}' must be a table")
    unknown = sorted(set(table) - set(rules))
    if unknown:
        allowed = ", ".join(sorted(rules))
        raise InputError(f"{source}: unknown key '{prefix}{unknown[0]}' (allowed: {allowed})")
    out: dict[str, Any] = {}
    for key, rule in rules.items():
        if key in table:
            try:
                out[key] = rule.check(table[key])
            except ValueError as exc:
                raise InputError(f"{source}: field '{prefix}{key}' must be {exc}") from None
        elif key in defaults:
            out[key] = defaults[key]
        elif key in required:
            raise InputError(f"{source}: missing field '{prefix}{key}' ({rule.describe()})")
        else:
            out[key] = None
    return out
