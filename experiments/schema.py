"""Reading and validating scenario TOML files (stdlib ``tomllib``).

Every field is checked: unknown keys, wrong types and out-of-range values raise
:class:`~experiments.errors.InputError` with one line naming the file, the field
and the allowed range.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from experiments.errors import InputError


def load_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; a missing file or bad TOML becomes an InputError."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such scenario file")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p}: invalid TOML: {exc}") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {exc.strerror}") from None


def apply_overrides(data: dict[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """A copy of a parsed scenario with ``TABLE.KEY=VALUE`` overrides applied.

    ``VALUE`` is a TOML value (``10``, ``true``, ``[57.0, 59.0]``, ``"game"``), so the
    override is typed exactly as the file would be; the result is validated like
    the file itself. A top-level key has no dot (``name=...`` is refused: the
    name is derived, see :func:`override_suffix`).
    """
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in data.items()}
    for item in overrides:
        key, sep, text = item.partition("=")
        parts = key.strip().split(".")
        if not sep or not all(parts) or len(parts) > 2 or parts == ["name"]:
            raise InputError(f"--set {item!r}: expected TABLE.KEY=VALUE (e.g. model.nu_mps2=0.01)")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            raise InputError(
                f"--set {item!r}: {text.strip()!r} is not a TOML value "
                '(numbers, true/false, [lists], "strings")'
            ) from None
        if len(parts) == 1:
            out[parts[0]] = value
            continue
        table = out.setdefault(parts[0], {})
        if not isinstance(table, dict):
            raise InputError(f"--set {item!r}: {parts[0]!r} is not a table")
        table[parts[1]] = value
    return out


def override_suffix(overrides: Sequence[str]) -> str:
    """``+key=value`` per override, file-name safe: appended to the scenario's name so
    that results of an overridden scenario never land in the original's files."""
    squeezed = (o.replace(" ", "") for o in overrides)
    safe = ("".join(c if c.isalnum() or c in "._=-," else "_" for c in o) for o in squeezed)
    return "".join(f"+{o}" for o in safe)


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
