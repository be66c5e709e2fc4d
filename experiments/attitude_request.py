"""The ``attitude`` command's request, validated: the scenario read with its overrides,
the controller and its loop, the estimators and noises (:func:`request`; one-line
``InputError`` otherwise). ``kvi attitude``, ``kvi attitude-tightness`` and
:func:`kalman_vs_infoset.api_attitude.run_attitude` read their scenarios through it.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.attitude_loops import (
    LOOPS,
    AttitudeLoop,
    controllers_like,
    loop_of,
    same_loop,
)
from kalman_vs_infoset.experiments.errors import InputError


@dataclass(frozen=True)
class AttitudeRequest:
    """One ``attitude`` command, validated: what runs, where, and on which scenario.

    ``scenario`` is the file's tables (with the overrides, without the top-level
    ``estimator``, which the choices replace): the loop's ``prepare`` types them, and
    they are written beside the tables and compared on resume.
    """

    source: str
    name: str
    controller: str
    loop: AttitudeLoop
    estimators: tuple[str, ...]
    noises: tuple[str, ...]
    runs: int
    seed: int
    out: Path
    scenario: Mapping[str, Any]


def _choice(value: Any, what: str, source: str) -> str | None:
    if what == "estimator" and isinstance(value, dict):  # the intercept's [estimator.<name>]
        from kalman_vs_infoset.experiments.sim.estimator_tables import not_a_table

        raise InputError(f"{source}: {not_a_table()}")
    if value is not None and not isinstance(value, str):
        raise InputError(f"{source}: field '{what}' must be a string")
    return value


def request(args: argparse.Namespace) -> AttitudeRequest:
    """The command's :class:`AttitudeRequest` (``InputError`` of one line otherwise)."""
    from kalman_vs_infoset.experiments.scenario import read
    from kalman_vs_infoset.experiments.sim.intercept_config import check_name

    # (how the overrides were given: --set, or run_attitude's keywords)
    data, source = read(args.scenario, args.overrides, kind="attitude",
                        via=getattr(args, "via", "--set"))  # fmt: skip
    given = _choice(data.get("controller"), "controller", source)
    default_est = _choice(data.pop("estimator", None), "estimator", source)
    controller = args.controller if args.controller is not None else given
    if controller is None:
        raise InputError(f"{args.scenario}: no --controller and no top-level 'controller' key")
    loop = loop_of(controller)
    if args.controller is not None and given in LOOPS and not same_loop(given, controller):
        raise InputError(  # another simulation's scenario
            f"{source}: field 'controller' {given!r} makes it a scenario of "
            f"{controllers_like(given)}; --controller {controller} runs scenarios of "
            f"{controllers_like(controller)}"
        )
    noises = tuple(args.noise or ["none"])
    estimators = args.estimators
    if estimators is None:
        from kalman_vs_infoset.estim import registry

        # exact measurements: read as the state; noisy ones: the reference set
        exact = noises == ("none",)
        fallback = (
            registry.first_with_role("attitude", "exact")
            if exact
            else registry.reference("attitude")
        ).name
        try:
            estimators = options.split_list(
                default_est or fallback, registry.names("attitude"), "attitude estimators"
            )
        except ValueError as exc:
            raise InputError(f"{source}: field 'estimator': {exc}") from None
    try:
        name = check_name(data["name"])
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None
    return AttitudeRequest(
        source=source,
        name=name,
        controller=controller,
        loop=loop,
        estimators=tuple(estimators),
        noises=noises,
        runs=args.runs,
        seed=args.seed,
        out=options.out_folder(args.out, Path("results") / "attitude" / name),
        scenario=MappingProxyType(data),
    )
