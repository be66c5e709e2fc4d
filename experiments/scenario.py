"""Reading scenario files: TOML, ``--set`` overrides, typed validation, one-line errors.

Above the simulations (:mod:`kalman_vs_infoset.experiments.sim`): a file is read (UTF-8 TOML, stdlib
``tomllib``), overridden, and validated by the simulation's typed tables (pydantic);
every problem becomes an :class:`~experiments.errors.InputError` of one line naming the
file and the field, which the command line prints with exit status 2.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, TypeVar

from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.sim.fields import first_error
from kalman_vs_infoset.experiments.sim.intercept_config import SAFE_NAME, InterceptScenario
from pydantic import BaseModel, ValidationError

from kalman_vs_infoset import data as bundled

M = TypeVar("M", bound=BaseModel)

Kind = Literal["intercept", "attitude"]

#: top-level tables only an intercept scenario has: the attitude loops' scenario tables
#: (RwScenario, CmgScenario, GyrostatScenario, which refuse unknown keys) share only
#: these three with it, and their ``estimator`` is a string, not a table
INTERCEPT_ONLY = frozenset(InterceptScenario.model_fields) - {"name", "description", "estimator"}

#: the commands that run a scenario of each kind (messages)
RUN_WITH: dict[Kind, str] = {
    "intercept": "`kvi intercept` (or compare, sweep, adversaries, tightness)",
    "attitude": "`kvi attitude`",
}


def scenario_folder(folder: str | Path | None) -> Path:
    """``--scenarios``: a folder of scenario files, the bundled one when ``None``."""
    if folder is None:
        return bundled.path("scenarios")
    p = Path(folder)
    if not p.is_dir():
        raise InputError(f"--scenarios {p}: not a folder")
    return p


def resolve(name_or_path: str | Path) -> Path:
    """The scenario file a command argument names: an existing file, else a bundled
    scenario of that name (``kp_fig3`` or ``kp_fig3.toml``: :mod:`kalman_vs_infoset.data`);
    neither is an InputError of one line."""
    p = Path(name_or_path)
    if p.is_file():
        return p
    if p.parent == Path(".") and p.suffix in ("", ".toml"):
        try:
            return bundled.scenario_file(p.name)
        except KeyError:
            pass
    if p.is_dir():
        raise InputError(f"{p}: a folder, not a scenario file (a TOML file, or a bundled name)")
    raise InputError(
        f"{p}: no such scenario file, nor a bundled scenario (`kvi scenarios` lists them)"
    )


def load_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file (a path or a bundled scenario's name: :func:`resolve`); a
    missing, unreadable, non-UTF-8, empty or bad file is an InputError of one line."""
    p = resolve(path)
    try:
        text = p.read_bytes().decode("utf-8-sig")  # a byte-order mark is allowed
    except UnicodeDecodeError as exc:
        raise InputError(
            f"{p}: not UTF-8 text (byte {exc.start}); scenario files are UTF-8 TOML"
        ) from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p}: invalid TOML: {exc}") from None
    if not data:  # an empty file would silently run the built-in defaults
        raise InputError(f"{p}: the scenario is empty (no key, no table)")
    return data


def scenario_kind(data: Mapping[str, Any]) -> Kind | None:
    """The kind of scenario a file's tables describe, None when they do not say.

    Parameters
    ----------
    data : mapping
        The file's top-level keys and tables (before any ``--set``).

    Returns
    -------
    {"intercept", "attitude"} or None
        ``"attitude"`` when there is a top-level ``controller`` (every attitude loop's
        scenario has that key, which selects the loop; the intercept's has none),
        ``"intercept"`` when there is an intercept-only table (:data:`INTERCEPT_ONLY`)
        or the ``estimator`` is a table, else None (a file this small is judged by
        the loader's own field checks).
    """
    if "controller" in data:
        return "attitude"
    if isinstance(data.get("estimator"), dict) or not INTERCEPT_ONLY.isdisjoint(data):
        return "intercept"
    return None


def check_kind(data: Mapping[str, Any], expected: Kind, source: str | Path) -> None:
    """Refuse (InputError of one line) a scenario of the other kind than ``expected``,
    naming the command that runs it; its fields would otherwise be refused one by one
    (an attitude scenario's ``controller`` is an unknown key of the intercept's)."""
    kind = scenario_kind(data)
    if kind is not None and kind != expected:
        raise InputError(f"{source} is an {kind} scenario: run it with {RUN_WITH[kind]}")


def dotted_fields(tables: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """The fields of nested tables by their dotted keys (``{"model": {"dt_s": 0.5}}``:
    ``{"model.dt_s": 0.5}``), the form ``--set TABLE.KEY=VALUE`` names them in."""
    out: dict[str, Any] = {}
    for key, value in tables.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        out.update(dotted_fields(value, name) if isinstance(value, Mapping) else {name: value})
    return out


def apply_overrides(data: dict[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """A copy of a parsed scenario with ``TABLE.KEY=VALUE`` overrides applied.

    ``VALUE`` is a TOML value (``10``, ``true``, ``[57.0, 59.0]``, ``"game"``), so the
    override is typed exactly as the file would be; the result is validated like the
    file itself. Keys may be nested (``estimator.infoset.n_sections=60``); a top-level
    key has no dot, and ``name`` is refused (it is derived: :func:`override_suffix`).
    """

    def copy(v: Any) -> Any:
        return {k: copy(x) for k, x in v.items()} if isinstance(v, dict) else v

    out = copy(data)
    keys = [item.partition("=")[0].strip() for item in overrides]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:  # the last one would silently win
        raise InputError(f"--set {twice[0]} given twice; give each key once")
    for item in overrides:
        key, sep, text = item.partition("=")
        parts = key.strip().split(".")
        if parts == ["name"]:
            raise InputError(
                f"--set {item!r}: the name is not set: it is the scenario's, with a "
                "+key=value suffix per override (results of an override never land in "
                "the original's files)"
            )
        # (the deepest field: attitude.estimator_options.<name>.<option>)
        if not sep or not all(parts) or len(parts) > 4:
            raise InputError(f"--set {item!r}: expected TABLE.KEY=VALUE (e.g. model.nu_mps2=0.01)")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            raise InputError(
                f"--set {item!r}: {text.strip()!r} is not a TOML value "
                '(numbers, true/false, [lists], "strings")'
            ) from None
        table = out
        for part in parts[:-1]:
            table = table.setdefault(part, {})
            if not isinstance(table, dict):
                raise InputError(f"--set {item!r}: {part!r} is not a table")
        table[parts[-1]] = value
    return out


#: longest override suffix of a scenario's name (the name is part of every result
#: file's name, and a file name has at most 255 bytes)
MAX_SUFFIX = 96


def toml_value(value: Any) -> str:
    """``value`` as the TOML text of a ``--set`` item: numbers, booleans, strings and
    lists of them (numpy scalars and arrays as their lists; a tuple as a list). Not
    JSON's text: TOML writes ``nan`` and ``inf`` where JSON writes ``NaN`` and
    ``Infinity``."""
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        value = value.tolist()
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return json.dumps(value)


def _name_safe(text: str, keep: str) -> str:
    """``text`` with every character but ASCII letters, digits and those of ``keep``
    made ``_``: what a scenario's name allows (a letter such as "é" is one to
    ``str.isalnum``, and was kept, then refused by the name check)."""
    return "".join(c if (c.isascii() and c.isalnum()) or c in keep else "_" for c in text)


def override_suffix(overrides: Sequence[str]) -> str:
    """``+key=value`` per override, file-name safe: appended to the scenario's name so
    that results of an overridden scenario never land in the original's files. Past
    :data:`MAX_SUFFIX` characters the overrides that do not fit are named by a hash of
    all of them (``+N_more_<hash>``): distinct override lists keep distinct names. The
    overrides are taken in the order of their keys (a key is set once): the same
    overrides given in another order name the same files, and resume them. Where one
    key holds another (a table and one of its fields), the later one wins, so their
    order is kept."""
    keys = [o.split("=", 1)[0].strip() for o in overrides]
    nested = any(b.startswith(a + ".") for a in keys for b in keys)
    if not nested:
        overrides = sorted(overrides, key=lambda o: (o.split("=", 1)[0].strip(), o))
    squeezed = (o.replace(" ", "") for o in overrides)
    safe = [_name_safe(o, "._=-,") for o in squeezed]
    # a value's '..' (a text with an ellipsis) would make the name a path's parent
    safe = [o.replace("..", "_") for o in safe]
    full = "".join(f"+{o}" for o in safe)
    if len(full) <= MAX_SUFFIX:
        return full
    digest = hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:12]
    # the most leading overrides that fit beside the tail naming the rest (0 always do)
    k = max(
        k
        for k in range(len(safe))
        if sum(len(o) + 1 for o in safe[:k]) + len(f"+{len(safe) - k}_more_{digest}") <= MAX_SUFFIX
    )
    return "".join(f"+{o}" for o in safe[:k]) + f"+{len(safe) - k}_more_{digest}"


def default_name(path: str | Path) -> str:
    """The file's stem made result-file safe (an explicit ``name`` is checked instead)."""
    stem = _name_safe(Path(path).stem, "._=+,-")
    stem = stem.replace("..", "_").lstrip(".") or "scenario"
    return stem if SAFE_NAME.match(stem) else "scenario"


def validate(
    model: type[M], data: dict[str, Any], source: str, prefix: str = "", context=None
) -> M:
    """``model`` validated from ``data`` (``context``: pydantic's validation context);
    the first problem as one line naming the file."""
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        raise InputError(f"{source}: {first_error(exc, prefix, model)}") from None
    except ValueError as exc:  # a check outside pydantic's own
        raise InputError(f"{source}: {exc}") from None


def read(
    path: str | Path, overrides: Sequence[str] = (), kind: Kind = "attitude", via: str = "--set"
) -> tuple[dict[str, Any], str]:
    """The file's tables with the overrides applied, the scenario's name set (the file's
    stem unless given; ``+key=value`` per override) and the source for messages.

    ``kind`` is the kind of scenario the caller runs: a file of the other kind is
    refused in one line naming its command (:func:`check_kind`, judged on the file
    itself, not on the overrides). The attitude loops read their tables here as they
    are (the default); :func:`load_scenario` reads the intercept's.
    """
    data = load_toml(path)
    check_kind(data, kind, path)
    data.setdefault("name", default_name(path))
    if not isinstance(data["name"], str):
        raise InputError(f"{path}: field 'name' must be a string")
    if not overrides:
        return data, str(path)
    data = apply_overrides(data, overrides)
    data["name"] = data["name"] + override_suffix(overrides)
    return data, f"{path} (with {via})"  # how the caller gave them: --set, or keywords


def load_scenario(
    path: str | Path,
    overrides: Sequence[str] = (),
    via: str = "--set",
    auxiliary_truth: bool = False,
) -> InterceptScenario:
    """Read and validate an intercept scenario file (or a bundled scenario by name),
    with optional ``TABLE.KEY=VALUE`` overrides (:func:`apply_overrides`; the name gets a
    ``+key=value`` suffix each). ``auxiliary_truth``: for a command whose truth is the
    auxiliary model itself (``tightness``), whose truth feels no differential gravity
    to check against ``nu``."""
    data, source = read(path, overrides, kind="intercept", via=via)
    context = {"auxiliary_truth": True} if auxiliary_truth else None
    sc = validate(InterceptScenario, data, source, context=context)
    _warn_unused(sc, overrides, via)
    return sc


def estimator_option(item: str) -> tuple[str, str, str] | None:
    """``(key, estimator, option)`` of an override ``estimator.NAME.OPTION=VALUE``;
    ``None`` for an override of any other field."""
    key = item.partition("=")[0].strip()
    parts = key.split(".")
    if len(parts) != 3 or parts[0] != "estimator":
        return None
    return key, parts[1], parts[2]


def _warn_unused(sc: InterceptScenario, overrides: Sequence[str], via: str) -> None:
    """One warning for each override of an estimator option that the estimator these
    options build does not read (``estimator.infoset.n_sections`` with the node set): its
    results would equal the original's under another name."""
    for item in overrides:
        found = estimator_option(item)
        if found is None or found[1] not in sc.estimator.options:
            continue
        key, name, option = found
        # (a plug-in may register any pydantic model: without the method, none)
        opts = sc.estimator.options_for(name)
        unused: dict[str, str] = getattr(opts, "unused_fields", dict)()
        if option in unused:
            warnings.warn(f"{via} {key} has no effect: {unused[option]}", UserWarning,
                          stacklevel=2)  # fmt: skip


def parse_scenario(data: dict[str, Any], source: str = "<scenario>") -> InterceptScenario:
    """An intercept scenario from tables already read (name "scenario" unless given)."""
    check_kind(data, "intercept", source)
    return validate(InterceptScenario, {"name": "scenario", **data}, source)


def field_doc(key: str) -> str | None:
    """The one-line doc (with its unit) of an intercept scenario's field ``TABLE.KEY``
    or ``estimator.NAME.OPTION`` (figure labels); ``None`` when the key names none."""
    from kalman_vs_infoset.estim import registry

    parts = key.split(".")
    model: Any = InterceptScenario
    if len(parts) == 3 and parts[0] == "estimator":
        try:
            model = registry.get("intercept", parts[1]).options
        except (KeyError, ValueError):
            return None
        parts = parts[2:]
    for depth, part in enumerate(parts):
        info = getattr(model, "model_fields", {}).get(part)
        if info is None:
            return None
        if depth == len(parts) - 1:
            return info.description or None
        model = info.annotation
    return None
