"""Estimators by name: ``(problem, name) -> (options model, factory)``.

A consumer (the intercept engagement, the attitude loops, the command line) never
names a concrete estimator class: it asks the registry for a name's
:class:`Registration`, validates the scenario's ``[estimator.<name>]`` table with the
registration's options model (pydantic, ``extra="forbid"``) and calls its factory.
Adding an estimator is one module and one :func:`register` call; a third-party
package registers its own through the entry-point group :data:`ENTRY_POINT_GROUP`
(each entry point names a callable that calls :func:`register`, or a module whose
import does).

Problems and what their factories receive (besides the validated options):

* ``"intercept"``: a :class:`estim.model.ChannelSetting` (channel model, closing-speed
  interval); beliefs start from a :class:`kalman_vs_infoset.estim.model.ChannelPrior`;
* ``"attitude"``: an :class:`estim.attitude_model.AttitudeModel`; beliefs start from an
  :class:`kalman_vs_infoset.estim.attitude_model.AttitudePrior` and are batched
  :class:`kalman_vs_infoset.estim.attitude_model.AttitudeBelief` values.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from kalman_vs_infoset.estim.base import Estimator
from pydantic import BaseModel

PROBLEMS = ("intercept", "attitude")
ENTRY_POINT_GROUP = "kalman_vs_infoset.estimators"
#: modules whose import registers the package's own estimators
BUILTIN = ("kalman_vs_infoset.estim.catalog", "kalman_vs_infoset.estim.catalog_sets")

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
    """

    name: str
    problem: str
    options: type[BaseModel]
    factory: Callable[[Any, Any], Estimator]
    doc: str = ""

    def build(self, options: BaseModel | dict[str, Any] | None, setting: Any) -> Estimator:
        """The estimator for validated ``options`` (a model, a table or None: defaults)."""
        if not isinstance(options, self.options):
            options = self.options.model_validate(options or {})
        return self.factory(options, setting)


def register(
    name: str,
    problem: str,
    options: type[BaseModel],
    factory: Callable[[Any, Any], Estimator],
    doc: str = "",
    replace: bool = False,
) -> Registration:
    """Register an estimator; a taken ``(problem, name)`` is an error unless ``replace``."""
    if problem not in PROBLEMS:
        raise ValueError(f"problem must be one of {PROBLEMS}, got {problem!r}")
    if not name or not name.replace("_", "").replace("-", "").isalnum():
        raise ValueError(f"estimator names are letters, digits, '_' and '-'; got {name!r}")
    if not (isinstance(options, type) and issubclass(options, BaseModel)):
        raise TypeError("options must be a pydantic model class")
    key = (problem, name)
    if key in _REGISTRY and not replace:
        raise ValueError(f"{problem} estimator {name!r} is already registered")
    reg = Registration(name, problem, options, factory, doc)
    _REGISTRY[key] = reg
    return reg


def unregister(problem: str, name: str) -> None:
    """Remove a registration (tests registering toy estimators clean up with this)."""
    _REGISTRY.pop((problem, name), None)


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    for module in BUILTIN:
        importlib.import_module(module)
    for entry in metadata.entry_points(group=ENTRY_POINT_GROUP):
        loaded = entry.load()
        if callable(loaded):
            loaded()


def names(problem: str) -> tuple[str, ...]:
    """Registered names of a problem, in registration order."""
    _load()
    return tuple(n for p, n in _REGISTRY if p == problem)


def get(problem: str, name: str) -> Registration:
    """The registration of ``name``; KeyError naming the allowed names otherwise."""
    _load()
    try:
        return _REGISTRY[(problem, name)]
    except KeyError:
        allowed = ", ".join(names(problem))
        raise KeyError(f"unknown {problem} estimator '{name}' (allowed: {allowed})") from None
