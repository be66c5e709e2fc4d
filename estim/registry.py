"""Estimators by name: ``(problem, name) -> Registration`` (options model, factory).

A consumer (the intercept engagement, the attitude loops, the command line) never
names a concrete estimator class: it asks the registry for a name's
:class:`Registration`, validates the options with the registration's options model
(pydantic, ``extra="forbid"``: an intercept scenario's ``[estimator.<name>]`` table, an
attitude scenario's ``[estimator_options.<name>]``) and builds the estimator.

Where registrations come from:

* the package's own: every family folder under a problem's package
  (:data:`PROBLEM_PACKAGES`, e.g. ``estim/intercept/gaussian/``) lists its estimators
  in ``REGISTRATIONS`` (:func:`declare`) in its ``__init__``; the folders are found by
  scanning, so adding an estimator is one new folder and touches no other file;
* a third-party package's: the entry-point group :data:`ENTRY_POINT_GROUP` (each entry
  point names a callable that calls :func:`register`, or a module whose import does);
  one that fails to load is left out with a warning (:data:`PLUGIN_ERRORS`).

Problems and what their factories receive (besides the validated options):

* ``"intercept"``: a :class:`kalman_vs_infoset.estim.intercept.model.ChannelSetting`
  (channel model, closing-speed interval); beliefs start from a
  :class:`kalman_vs_infoset.estim.intercept.model.ChannelPrior`;
* ``"attitude"``: an :class:`kalman_vs_infoset.estim.attitude.model.AttitudeModel`;
  beliefs start from an :class:`kalman_vs_infoset.estim.attitude.model.AttitudePrior`
  and are batched :class:`kalman_vs_infoset.estim.attitude.model.AttitudeBelief` values.

What a registration says about its estimator's part in the comparisons, so that no
command or figure names an estimator (each has a fallback, so a plug-in that says
nothing still runs everywhere):

* ``reference``: the problem's reference estimator (:func:`reference`);
* ``roles`` (:data:`ROLES`): e.g. the Kalman baselines a set is compared with
  (:func:`with_role`);
* ``label`` and ``colour``: how figures name and draw it (default: its name, and a
  spare colour chosen by name in the figures).
"""

from __future__ import annotations

import importlib
import pkgutil
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from kalman_vs_infoset.estim.base import Estimator
from pydantic import BaseModel

PROBLEMS = ("intercept", "attitude")
#: the packages whose sub-packages (the family folders) register the built-in estimators
PROBLEM_PACKAGES = {p: f"kalman_vs_infoset.estim.{p}" for p in PROBLEMS}
ENTRY_POINT_GROUP = "kalman_vs_infoset.estimators"
#: listing position of a registration that gives none (after the built-in ones)
LAST = 1000
#: the parts an estimator may declare it plays (:func:`with_role`)
ROLES = {
    "baseline": "a Kalman-type baseline the reference set estimator is compared with",
    "yardstick": "the baseline in whose step cost other costs are stated (kvi bench)",
    "exact": "reads the measurement as the state (exact with exact measurements)",
}

_REGISTRY: dict[tuple[str, str], Registration] = {}
_loaded = False


@dataclass(frozen=True)
class Registration:
    """One registered estimator.

    Attributes
    ----------
    name : str
        Its name on the command line and in ``[estimator.<name>]`` tables.
    problem : {"intercept", "attitude"}
        The problem it estimates.
    options : type[pydantic.BaseModel]
        Its options (each field with type, bounds, default and a one-line doc).
    factory : callable
        ``factory(options, setting) -> Estimator`` (setting: module docstring).
    doc : str
        One line for listings.
    rank : int
        Position in listings (ties: registration order).
    reference : bool
        The problem's reference estimator: the set the seed's game adversary reasons
        with (:func:`reference`).
    roles : tuple of str
        The parts it plays in the comparisons (keys of :data:`ROLES`; :func:`with_role`).
    label : str
        Its name in figure legends, in words ("" : its name; :attr:`words`).
    colour : str
        Its colour in figures, a matplotlib colour ("" : the figures choose one).
    trace_fields : tuple of str
        The quantities its beliefs report to a trace beside the generic ones
        (``Belief.trace_fields()``: the set's size, a filter's gate), names with units;
        the trace tables have a column for each field any registration declares.
    """

    name: str
    problem: str
    options: type[BaseModel]
    factory: Callable[[Any, Any], Estimator]
    doc: str = ""
    rank: int = LAST
    reference: bool = False
    roles: tuple[str, ...] = ()
    label: str = ""
    colour: str = ""
    trace_fields: tuple[str, ...] = ()

    @property
    def words(self) -> str:
        """Its name in figure legends: the label, or the name without one."""
        return self.label or self.name

    def validate(self, options: BaseModel | dict[str, Any] | None) -> BaseModel:
        """``options`` validated by the options model (a table or None: the defaults)."""
        if isinstance(options, self.options):
            return options
        return self.options.model_validate(options or {})

    def build(self, options: BaseModel | dict[str, Any] | None, setting: Any) -> Estimator:
        """The estimator for ``options`` (a model, a table or None: defaults)."""
        return self.factory(self.validate(options), setting)


def _options_build(options: Any, setting: Any) -> Estimator:
    return options.build(setting)


def declare(
    name: str,
    problem: str,
    options: type[BaseModel],
    factory: Callable[[Any, Any], Estimator] | None = None,
    doc: str = "",
    rank: int = LAST,
    reference: bool = False,
    roles: tuple[str, ...] = (),
    label: str = "",
    colour: str = "",
    trace_fields: tuple[str, ...] = (),
) -> Registration:
    """A checked registration, not yet registered: what a family folder lists in its
    ``REGISTRATIONS`` (and :func:`register` adds).

    ``factory`` defaults to the options model's own ``build(setting)``
    (:class:`kalman_vs_infoset.estim.options.EstimatorOptions`).
    """
    if problem not in PROBLEMS:
        raise ValueError(f"problem must be one of {PROBLEMS}, got {problem!r}")
    if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
        raise ValueError(f"estimator names are letters, digits, '_' and '-'; got {name!r}")
    if not (isinstance(options, type) and issubclass(options, BaseModel)):
        raise TypeError("options must be a pydantic model class")
    # checked here, not at the first run or listing: a rank of "5" broke every later
    # listing (str < int), a factory of 3 failed every run, a str of trace fields
    # became its letters
    if factory is not None and not callable(factory):
        raise TypeError(f"factory must be callable (options, setting), got {factory!r}")
    if not isinstance(rank, int) or isinstance(rank, bool):
        raise TypeError(f"rank must be an integer, got {rank!r}")
    for what, names in (("roles", roles), ("trace_fields", trace_fields)):
        if isinstance(names, str) or not all(isinstance(n, str) for n in names):
            raise TypeError(f"{what} must be a tuple of names (str), got {names!r}")
    for what, text in (("doc", doc), ("label", label), ("colour", colour)):
        if not isinstance(text, str):
            raise TypeError(f"{what} must be a str, got {text!r}")
    if factory is None:
        if not callable(getattr(options, "build", None)):
            raise TypeError("give a factory, or an options model with build(setting)")
        factory = _options_build
    unknown = sorted(set(roles) - set(ROLES))
    if unknown:
        raise ValueError(f"unknown roles {unknown}; allowed: {', '.join(ROLES)}")
    return Registration(
        name, problem, options, factory, doc, rank, reference, tuple(roles), label, colour,
        tuple(trace_fields),
    )  # fmt: skip


def _add(reg: Registration, replace: bool) -> Registration:
    key = (reg.problem, reg.name)
    if key in _REGISTRY and not replace:
        raise ValueError(
            f"{reg.problem} estimator {reg.name!r} is already registered (replace=True "
            "takes its place)"
        )
    _REGISTRY[key] = reg
    return reg


def register(
    name: str,
    problem: str,
    options: type[BaseModel],
    factory: Callable[[Any, Any], Estimator] | None = None,
    doc: str = "",
    replace: bool = False,
    rank: int = LAST,
    reference: bool = False,
    roles: tuple[str, ...] = (),
    label: str = "",
    colour: str = "",
    trace_fields: tuple[str, ...] = (),
) -> Registration:
    """Register an estimator; a taken ``(problem, name)`` is an error unless ``replace``.

    The built-in estimators are loaded first, so ``replace=True`` replaces one of them
    whenever it is called (also before the first lookup). Arguments: :func:`declare`.
    """
    _load()
    reg = declare(
        name, problem, options, factory, doc, rank, reference, roles, label, colour, trace_fields
    )
    return _add(reg, replace)


def unregister(problem: str, name: str) -> None:
    """Remove a registration (tests registering toy estimators clean up with this)."""
    _REGISTRY.pop((problem, name), None)


def family_modules(problem: str) -> list[str]:
    """The family folders of a problem's package, as module names (scanned, sorted)."""
    package = importlib.import_module(PROBLEM_PACKAGES[problem])
    prefix = package.__name__ + "."
    return sorted(prefix + m.name for m in pkgutil.iter_modules(package.__path__) if m.ispkg)


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True  # first: a plug-in's register() call comes back here
    for problem in PROBLEMS:
        for module in family_modules(problem):
            for reg in getattr(importlib.import_module(module), "REGISTRATIONS", ()):
                _add(reg, replace=False)
    for entry in metadata.entry_points(group=ENTRY_POINT_GROUP):
        _load_plugin(entry)


#: the plug-ins that failed to load, ``(entry point, error)``: each is left out with one
#: warning, so that one broken installation does not stop every command (nor the
#: plug-ins after it)
PLUGIN_ERRORS: list[tuple[str, str]] = []


def _load_plugin(entry: metadata.EntryPoint) -> None:
    """Load one entry point (a callable that registers, or a module whose import does);
    on any error its registrations so far are undone, the error is recorded in
    :data:`PLUGIN_ERRORS` and warned about in one line (``RuntimeWarning``)."""
    before = dict(_REGISTRY)
    try:
        loaded = entry.load()
        if callable(loaded):
            loaded()
    except Exception as exc:  # a plug-in's failure is its own: the rest still runs
        _REGISTRY.clear()  # back to before it: also a built-in it replaced
        _REGISTRY.update(before)
        dist = getattr(entry, "dist", None)
        where = f" of {dist.name} {dist.version}" if dist is not None else ""
        error = f"{type(exc).__name__}: {exc}".splitlines()[0]
        PLUGIN_ERRORS.append((f"{entry.name} = {entry.value}{where}", error))
        # attributed to the plug-in, not to a line of ours: Python's default display
        # then has no source line to print under it (one line, as the commands say it)
        warnings.warn_explicit(
            f"estimator plug-in {entry.name!r} ({entry.value}{where}) is left out: {error}",
            RuntimeWarning,
            filename=f"estimator plug-in {entry.name}",
            lineno=0,
            module=__name__,
        )


def _known(problem: str) -> str:
    """``problem`` if it is one of :data:`PROBLEMS`, else ``ValueError`` naming them (a
    misspelt or swapped argument listed no estimator, or called a name unknown)."""
    if problem not in PROBLEMS:
        raise ValueError(f"unknown problem {problem!r} (allowed: {', '.join(PROBLEMS)})")
    return problem


def names(problem: str) -> tuple[str, ...]:
    """Registered names of a problem, by listing rank (then registration order)."""
    _known(problem)
    _load()
    regs = [r for (p, _), r in _REGISTRY.items() if p == problem]
    return tuple(r.name for r in sorted(regs, key=lambda r: r.rank))


def registrations(problem: str) -> tuple[Registration, ...]:
    """The registrations of a problem, by listing rank (then registration order)."""
    _known(problem)
    _load()
    regs = [r for (p, _), r in _REGISTRY.items() if p == problem]
    return tuple(sorted(regs, key=lambda r: r.rank))


class UnknownEstimator(KeyError, ValueError):
    """An estimator name that is not registered: a ``KeyError`` (a lookup that failed)
    and a ``ValueError`` (a bad argument, as the library's other unknown names raise);
    ``str()`` is the message itself, without ``KeyError``'s quotes."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def get(problem: str, name: str) -> Registration:
    """The registration of ``name``; :class:`UnknownEstimator` (a ``KeyError`` and a
    ``ValueError``) naming the allowed names otherwise (ValueError for a problem not in
    :data:`PROBLEMS`)."""
    _known(problem)
    _load()
    try:
        return _REGISTRY[(problem, name)]
    except (KeyError, TypeError):  # TypeError: an unhashable name (a list of names)
        allowed = ", ".join(names(problem))
        raise UnknownEstimator(
            f"unknown {problem} estimator {name!r} (allowed: {allowed})"
        ) from None


def reference(problem: str) -> Registration:
    """The problem's reference estimator (the first registered with ``reference=True``)."""
    _known(problem)
    _load()
    for (p, _), reg in _REGISTRY.items():
        if p == problem and reg.reference:
            return reg
    raise LookupError(f"no reference {problem} estimator is registered")


def with_role(problem: str, role: str) -> tuple[Registration, ...]:
    """The registrations of ``problem`` that declare ``role``, by listing rank."""
    if role not in ROLES:
        raise ValueError(f"unknown role {role!r}; allowed: {', '.join(ROLES)}")
    _known(problem)
    _load()
    regs = [r for (p, _), r in _REGISTRY.items() if p == problem and role in r.roles]
    return tuple(sorted(regs, key=lambda r: r.rank))


def first_with_role(problem: str, role: str) -> Registration:
    """The first registration of ``problem`` declaring ``role`` (LookupError if none)."""
    regs = with_role(problem, role)
    if not regs:
        raise LookupError(f"no {problem} estimator declares the role {role!r}")
    return regs[0]


def by_name(name: str) -> tuple[Registration, ...]:
    """The registrations called ``name``, over all problems (a figure knows the name
    of a curve's estimator, not always its problem)."""
    _load()
    return tuple(r for (_, n), r in _REGISTRY.items() if n == name)
