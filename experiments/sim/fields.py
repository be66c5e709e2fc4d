"""Typed configuration tables of the simulations (pydantic v2, ``extra="forbid"``).

Every field is declared once: type, bounds, default, unit (in its name) and a one-line
doc. Invalid values raise ``pydantic.ValidationError`` (a ``ValueError``); the command
line turns the first error into one line naming the file and the field
(:mod:`kalman_vs_infoset.experiments.scenario`).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    TypeAdapter,
    ValidationError,
)

#: no silent conversion (a string is not a number, true is not 1); lists become tuples
STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)


class Table(BaseModel):
    """A scenario table: strict, unknown keys refused, immutable."""

    model_config = STRICT


def _as_tuple(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def _ordered(value: tuple[float, float]) -> tuple[float, float]:
    if value[0] > value[1]:
        raise ValueError("lo must be <= hi")
    return value


def field(default: Any = ..., doc: str = "", **bounds: Any) -> Any:
    """A declared field: ``default`` (``...``: required), a one-line ``doc`` and bounds
    (``ge``, ``gt``, ``le``, ``lt``) applied to the value or to each item of a list."""
    return Field(default, description=doc, **bounds)


def float_bounds(
    lo: float | None = None, hi: float | None = None, open_lo: bool = False, open_hi: bool = False
) -> Any:
    """The bounds of a float field, ``Annotated[float, float_bounds(lo, hi)]``: a finite
    value in ``[lo, hi]`` (open ends on request; ints accepted)."""
    bounds: dict[str, Any] = {}
    if lo is not None:
        bounds["gt" if open_lo else "ge"] = lo
    if hi is not None:
        bounds["lt" if open_hi else "le"] = hi
    return Field(allow_inf_nan=False, **bounds)


#: the largest moment of inertia a scenario takes, kg m^2: the largest spacecraft (the
#: ISS) is about 1e8; far beyond, the filters' disturbance variances overflow (1e300
#: did: numpy's warnings, then a failed eigenvalue solve)
MAX_INERTIA_KGM2 = 1e12


def int_bounds(lo: int | None = None, hi: int | None = None) -> Any:
    """The bounds of an integer field, ``Annotated[int, int_bounds(lo, hi)]``."""
    return Field(ge=lo, le=hi)


# The shapes are generic aliases over the item type (``Vector3[Annotated[float, ...]]``)
# rather than functions returning types, so that type checkers read them as types.
_Item = TypeVar("_Item")

#: a list of 2, 3, 4 or 6 items (TOML array), stored as a tuple
Vector2 = Annotated[
    tuple[_Item, _Item], BeforeValidator(_as_tuple), Field(json_schema_extra={"n": 2})
]
Vector3 = Annotated[
    tuple[_Item, _Item, _Item], BeforeValidator(_as_tuple), Field(json_schema_extra={"n": 3})
]
Vector4 = Annotated[
    tuple[_Item, _Item, _Item, _Item],
    BeforeValidator(_as_tuple),
    Field(json_schema_extra={"n": 4}),
]
Vector6 = Annotated[
    tuple[_Item, _Item, _Item, _Item, _Item, _Item],
    BeforeValidator(_as_tuple),
    Field(json_schema_extra={"n": 6}),
]

#: a list ``[lo, hi]`` with ``lo <= hi``, stored as a tuple
Interval = Annotated[
    tuple[_Item, _Item],
    BeforeValidator(_as_tuple),
    AfterValidator(_ordered),
    Field(json_schema_extra={"interval": True}),
]

POSITIVE = Annotated[float, float_bounds(0.0, open_lo=True)]
NONNEGATIVE = Annotated[float, float_bounds(0.0)]


# -- one line per error -------------------------------------------------------------------
def _field_info(model: type[BaseModel] | None, loc: tuple) -> Any:
    """The FieldInfo at ``loc`` inside ``model`` (through nested tables), or None."""
    info = None
    for part in loc:
        if model is None or not isinstance(part, str) or part not in model.model_fields:
            return info if isinstance(part, int) else None
        info = model.model_fields[part]
        nested = [
            t
            for t in (info.annotation, *getattr(info.annotation, "__args__", ()))
            if isinstance(t, type) and issubclass(t, BaseModel)
        ]
        model = nested[0] if nested else None
    return info


def _describe_schema(s: dict[str, Any]) -> str:
    if "anyOf" in s:
        parts = [_describe_schema(x) for x in s["anyOf"] if x.get("type") != "null"]
        return " or ".join(parts)
    if "$ref" in s:  # a nested table
        return "a table"
    if "enum" in s or "const" in s:
        return "one of " + ", ".join(repr(v) for v in s.get("enum", [s.get("const")]))
    kind = s.get("type")
    if kind in ("number", "integer"):
        lo = s.get("minimum", s.get("exclusiveMinimum", -math.inf))
        hi = s.get("maximum", s.get("exclusiveMaximum", math.inf))
        # an unbounded end is open: infinities are not numbers a field takes
        lb = "(" if "exclusiveMinimum" in s or math.isinf(lo) else "["
        rb = ")" if "exclusiveMaximum" in s or math.isinf(hi) else "]"
        what = "an integer" if kind == "integer" else "a number"
        return f"{what} in {lb}{lo:g}, {hi:g}{rb}"
    if kind == "boolean":
        return "true or false"
    if kind == "string":
        return "a string"
    if kind == "array" and "prefixItems" in s:
        items = s["prefixItems"]
        if s.get("interval"):
            return f"a list [lo, hi] with lo <= hi, each {_describe_schema(items[0])}"
        return f"a list of {len(items)} values, each {_describe_schema(items[0])}"
    if kind == "object":
        return "a table"
    return "valid"


def describe(model: type[BaseModel] | None, loc: tuple) -> str | None:
    """What the field at ``loc`` allows, in words (None when unknown)."""
    info = _field_info(model, loc)
    if info is None:
        return None
    try:
        # a type form built at run time (mypy cannot type Annotated[...] of a tuple)
        hint: Any = (
            Annotated[(info.annotation, *info.metadata)] if info.metadata else info.annotation
        )
        schema = TypeAdapter(hint).json_schema()
    except Exception:  # noqa: BLE001 - a description is a courtesy
        return None
    if "anyOf" in schema:  # optional: what it must be when given
        schema = next((x for x in schema["anyOf"] if x.get("type") != "null"), schema)
    if isinstance(loc[-1], int) and "prefixItems" in schema:
        schema = schema["prefixItems"][min(loc[-1], len(schema["prefixItems"]) - 1)]
    return _describe_schema(schema)


def first_error(
    exc: ValidationError, prefix: str = "", model: type[BaseModel] | None = None
) -> str:
    """The first error of ``exc`` as one line naming the field and what it allows."""
    err = exc.errors()[0]
    loc = tuple(p for p in err["loc"] if p != "options")
    names = [str(p) for p in loc if isinstance(p, str)]
    dotted = prefix + ".".join(names)
    kind, msg = err["type"], str(err["msg"])
    if kind == "extra_forbidden":
        parent = _field_info(model, loc[:-1])
        fields = model.model_fields if len(loc) == 1 and model else None
        if parent is not None:
            sub = [t for t in (parent.annotation, *getattr(parent.annotation, "__args__", ()))
                   if isinstance(t, type) and issubclass(t, BaseModel)]  # fmt: skip
            fields = sub[0].model_fields if sub else None
        names_ok = sorted(f for f in fields or () if f != "options")
        allowed = f" (allowed: {', '.join(names_ok)})" if names_ok else ""
        return f"unknown key '{dotted}'{allowed}"
    if kind == "missing" and loc and isinstance(loc[-1], int):  # a list too short
        loc, kind = loc[:-1], "too_short"
    if kind == "missing":
        what = describe(model, loc)
        return f"missing table '[{dotted}]'" if what == "a table" else f"missing field '{dotted}'"
    msg = msg.removeprefix("Value error, ")
    if kind == "value_error" and msg.startswith(("field ", "table ", "unknown key ")):
        return msg  # a table's own check: its message names the field (or the key)
    if kind == "value_error" and not names:
        return f"table '{prefix.rstrip('.')}': {msg}" if prefix else msg
    got = err.get("input")
    got = list(got) if isinstance(got, tuple) else got  # as written in TOML
    shown = "" if isinstance(got, dict) else f" (got {got!r})"
    what = describe(model, loc)
    if what is None:
        what = msg.removeprefix("Input should be ")
        # a table of tables (an estimator's options) in the words of every other table
        what = "a table" if what == "a valid dictionary" else what
    elif kind == "value_error":  # the field's own check refused a value of its type
        return f"field '{dotted}' ({what}): {msg}{shown}"
    return f"field '{dotted}' must be {what}{shown}"


#: a moment of inertia, kg m^2: positive, at most :data:`MAX_INERTIA_KGM2`
Inertia = Annotated[float, float_bounds(0.0, MAX_INERTIA_KGM2, open_lo=True)]
