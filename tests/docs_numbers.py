"""Reading printed numbers out of the docs and comparing them with results files.

Shared by ``test_docs_numbers.py`` (sentences) and ``test_docs_tables.py`` (tables). A
printed number agrees with a result when it is the result rounded to the printed digits
(half a unit of the last printed digit, plus a relative 1e-9 for the binary
representation); a number in scientific notation, to its printed significant digits.
"""

from __future__ import annotations

import ast
import inspect
import json
import re
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: a printed number: optional sign, digits, optional decimals and exponent
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e-?\d+)?")
#: the estimator names the tables print, by registry name
PRINTED_NAMES = {"EKF": "ekf", "UKF": "ukf", "H-infinity": "hinf", "particle filter": "pf"}


@cache
def results(path: str) -> dict | list:
    """A results file, read once: JSON, or a run table (Parquet) as a list of records."""
    if path.endswith(".parquet"):
        import pandas as pd  # only for run tables

        return pd.read_parquet(ROOT / path).to_dict(orient="records")
    return json.loads((ROOT / path).read_text(encoding="utf-8"))


def study_variant(path: str, scenario: str, noise: str) -> dict:
    """The one variant of a study's results file (``kvi fig5 --json``) run on
    ``scenario`` under ``noise``."""
    (row,) = [
        v for v in results(path)["variants"] if (v["scenario"], v["noise"]) == (scenario, noise)
    ]
    return row


def scenario_tables(name: str) -> dict:
    """A bundled scenario file's tables (``data/scenarios/NAME.toml``), as written."""
    import tomllib

    return tomllib.loads((ROOT / f"data/scenarios/{name}.toml").read_text(encoding="utf-8"))


def band_widths_pct(name: str, n_bands: int) -> list[float]:
    """Relative widths ``u_hi / u_lo - 1`` (per cent) of the scenario's closing-speed
    interval cut, as the node set cuts it, into ``n_bands`` equal pieces of ``u = 1/e``."""
    import numpy as np

    e_lo, e_hi = scenario_tables(name)["estimator"]["closing_speed_kmps"]
    u = np.linspace(1.0 / e_hi, 1.0 / e_lo, n_bands + 1)
    return [float(w) for w in 100.0 * (u[1:] / u[:-1] - 1.0)]


def speed_rows(stem: str) -> dict[str, dict]:
    """The rows of ``docs/results/speed/STEM.json`` (``kvi compare``), by noise."""
    return {r["noise"]: r for r in results(f"docs/results/speed/{stem}.json")["rows"]}


def speed_cpu_s(name: str) -> dict[str, float]:
    """CPU-s per noise of ``docs/results/speed/kp_fig5-NAME.json`` (``kvi compare``)."""
    return {noise: r["cpu_s"] for noise, r in speed_rows(f"kp_fig5-{name}").items()}


def paired_cpu_ratio(option: str, default: str) -> dict[str, float]:
    """CPU-time ratio per noise of ``speed/OPTION.json`` to ``speed/DEFAULT.json``, each
    measured twice alternately (``STEM`` and ``STEM-repeat``): the sums' ratio."""
    a, b = ([speed_rows(s), speed_rows(f"{s}-repeat")] for s in (option, default))
    return {n: (a[0][n]["cpu_s"] + a[1][n]["cpu_s"]) / (b[0][n]["cpu_s"] + b[1][n]["cpu_s"])
            for n in a[0]}  # fmt: skip


def speed_base_cpu_s() -> dict[str, float]:
    """The defaults' CPU-s per noise: the mean of the first row and the two repeats, the
    base the text's speed ratios are taken against."""
    runs = [speed_cpu_s(n) for n in ("default", "default-repeat", "default-repeat2")]
    return {n: sum(r[n] for r in runs) / len(runs) for n in runs[0]}


def _select(items: list, selector: str):
    """The one item of a list of records whose fields equal ``[field=value,...]``."""
    wanted = dict(pair.split("=", 1) for pair in selector[1:-1].split(","))
    found = [it for it in items if all(str(it.get(k)) == v for k, v in wanted.items())]
    if len(found) != 1:
        raise KeyError(f"{selector}: {len(found)} records match")
    return found[0]


def lookup(data, key: str):
    """The value at a ``/``-separated key: list items by index or by a selector
    ``[field=value,...]`` naming one record; a name holding ``/``, such as
    ``perfect/none``, is found by joining parts."""
    parts = key.split("/")
    while parts:
        part = parts.pop(0)
        if isinstance(data, list):
            data = _select(data, part) if part.startswith("[") else data[int(part)]
            continue
        while part not in data and parts:
            part += "/" + parts.pop(0)
        data = data[part]
    return data


def printed(doc: str, pattern: str) -> tuple[str, ...]:
    """The numbers a sentence of ``doc`` prints (the pattern's groups; the document's line
    breaks read as spaces); a sentence that is gone fails, naming the document."""
    flat = " ".join((ROOT / doc).read_text(encoding="utf-8").split())
    match = re.search(pattern, flat)
    assert match, f"{doc}: no sentence matches {pattern!r} (re-point it)"
    return match.groups()


#: what a formatted value of a checked f-string prints: at its end, a number, perhaps with
#: a parenthesis after it ("1.034 (seed 425, at 60 s)"), or two such joined by "and"; at
#: its start, that or a few words without digits (a label); inside it, anything short
#: between the literal parts
_ONE = r"-?[\d.]+(?:e-?\d+)?(?: \([^)]*\))?"
_END_VALUE = rf"{_ONE}(?: and {_ONE})?"
_START_VALUE, _INNER_VALUE = rf"(?:{_END_VALUE}|[A-Za-z_ ]{{1,40}}?)", r".{1,120}?"


def _fstring_pattern(node: ast.JoinedStr, assigned: dict[str, ast.expr]) -> str:
    """An f-string as a pattern; a value that names another f-string of the same test
    (``assigned``) reads as that one's pattern."""
    parts, out = node.values, []
    for i, v in enumerate(parts):
        inner = assigned.get(v.value.id) if isinstance(v, ast.FormattedValue) and isinstance(
            v.value, ast.Name) else None  # fmt: skip
        if isinstance(v, ast.Constant):
            out.append(re.escape(v.value))
        elif isinstance(inner, ast.JoinedStr):
            out.append(_fstring_pattern(inner, assigned))
        else:
            out.append(_START_VALUE if i == 0 else _END_VALUE if i == len(parts) - 1
                       else _INNER_VALUE)  # fmt: skip
    return "".join(out)


def searched_patterns(module) -> list[str]:
    """The sentences ``module``'s tests check, as regular expressions read from their
    source: the literal first argument of each ``_found(...)`` and ``re.search(...)``, and
    what each ``... in text`` looks for, written as a string or an f-string there or
    assigned to the name it tests (an f-string's literal parts stay, its values read as
    :data:`_START_VALUE`, :data:`_INNER_VALUE`, :data:`_END_VALUE`). An inventory counts
    what they match as checked: a pattern listed here is one a test checks."""
    out = []
    for func in ast.walk(ast.parse(inspect.getsource(module))):
        if not isinstance(func, ast.FunctionDef):
            continue
        assigned = {
            t.id: n.value
            for n in ast.walk(func)
            if isinstance(n, ast.Assign)
            for t in n.targets
            if isinstance(t, ast.Name)
        }
        for node in ast.walk(func):
            if isinstance(node, ast.Call) and node.args:
                f = node.func
                name = getattr(f, "id", None) or getattr(f, "attr", "")
                arg = node.args[0]
                if name in ("_found", "search") and isinstance(arg, ast.Constant):
                    out.append(arg.value)
            elif isinstance(node, ast.Compare) and isinstance(node.ops[0], ast.In):
                left = node.left
                if isinstance(left, ast.Name):
                    left = assigned.get(left.id, left)
                if isinstance(left, ast.JoinedStr):
                    out.append(_fstring_pattern(left, assigned))
                elif isinstance(left, ast.Constant) and isinstance(left.value, str):
                    out.append(re.escape(left.value))
    return out


def agrees(printed: str, value: float) -> bool:
    """Whether ``printed`` is ``value`` rounded to the printed digits."""
    mantissa, _, exponent = printed.partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    unit = 10.0 ** (int(exponent or 0) - decimals)  # of the last printed digit
    return abs(value - float(printed)) <= 0.5 * unit + 1e-9 * abs(value)


def agree_each(shown, values) -> None:
    """Each printed number agrees with its value (:func:`agrees`), in order, and there are
    as many of each."""
    values = list(values)
    assert len(shown) == len(values), (shown, values)
    for p, v in zip(shown, values, strict=True):
        assert agrees(p, float(v)), (p, v)


def mismatches(text: str, pattern: str, data, keys: tuple[str, ...]) -> list[str]:
    """What disagrees between a document's text and the results (empty: all agree).

    ``pattern`` has one group per printed number; every occurrence is checked, and a
    pattern that does not occur is reported (a rewritten sentence must be re-pointed).
    A key ``path::key`` reads another results file than ``data``.
    """
    found = re.findall(pattern, " ".join(text.split()))  # line breaks read as spaces
    if not found:
        return [f"pattern not in the document: {pattern!r}"]
    bad = []
    for groups in found:
        groups = (groups,) if isinstance(groups, str) else groups
        if len(groups) != len(keys):
            return [f"{pattern!r}: {len(groups)} groups for {len(keys)} keys"]
        for printed, key in zip(groups, keys, strict=True):
            source, _, inner = key.rpartition("::")  # a key in another results file
            value = lookup(results(source) if source else data, inner)
            if isinstance(value, str):  # a version or a name: printed as it is
                if printed != value:
                    bad.append(f"{key}: printed {printed}, results file {value}")
            elif not agrees(printed, float(value)):
                bad.append(f"{key}: printed {printed}, results file {float(value):.6g}")
    return bad


def tables(text: str) -> dict[str, list[list[str]]]:
    """The Markdown tables of a document: header line -> rows of cells (outside code
    blocks; the separator line dropped)."""
    out: dict[str, list[list[str]]] = {}
    header = None
    in_code = False
    for line in text.splitlines():
        if line.startswith("```"):
            in_code = not in_code
        if in_code or not line.startswith("|"):
            header = None
            continue
        if header is None:  # tables with the same header are read as one
            header = line.strip()
            out.setdefault(header, [])
        elif not set(line) <= set("|-: "):
            out[header].append([c.strip() for c in line.strip().strip("|").split("|")])
    return out


@dataclass(frozen=True)
class TableCheck:
    """A table of a document against the records of a results file.

    ``labels``: per label column, the record's field it names (the printed estimator
    names read through ``PRINTED_NAMES``); each row must name exactly one record.
    ``cells``: per number column, the record keys of the numbers printed in that cell,
    in order. A column in neither holds no number. ``column_labels``: for a table that
    spreads records over columns too (a pivot), the fields each column's header names.
    """

    doc: str
    header: str
    results: str
    records: str
    labels: dict[int, str]
    cells: dict[int, tuple[str, ...]]
    column_labels: dict[int, dict[str, str]] = field(default_factory=dict)


def table_mismatches(text: str, check: TableCheck, data) -> list[str]:
    """What disagrees between a document's table and its results file."""
    found = [rows for head, rows in tables(text).items() if head.startswith(check.header)]
    if len(found) != 1:
        return [f"{len(found)} tables start with {check.header!r}"]
    records = lookup(data, check.records) if check.records else data
    bad = []
    for cells in found[0]:
        sel = [
            f"{name}={PRINTED_NAMES.get(cells[col], cells[col])}"
            for col, name in check.labels.items()
        ]
        for col, keys in check.cells.items():
            extra = [f"{k}={v}" for k, v in check.column_labels.get(col, {}).items()]
            try:
                record = _select(records, "[" + ",".join(sel + extra) + "]")
            except KeyError as exc:
                bad.append(f"row {cells}: {exc}")
                continue
            printed = NUMBER.findall(cells[col])
            if len(printed) != len(keys):
                bad.append(f"row {cells[:2]}, column {col}: {printed} for keys {keys}")
                continue
            for p, key in zip(printed, keys, strict=True):
                value = float(lookup(record, key))
                if not agrees(p, value):
                    bad.append(f"row {cells[:2]}, {key}: printed {p}, results file {value:.6g}")
        left = [c for i, c in enumerate(cells) if i not in check.labels and i not in check.cells]
        bad += [f"row {cells[:2]}: unchecked number in {c!r}" for c in left if NUMBER.search(c)]
    return bad
