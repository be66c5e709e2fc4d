"""``python -m experiments attitude SCENARIO.toml [--controller NAME] [--noise ...]`` (SPEC 3.1).

Loads the scenario, takes the controller from ``--controller`` or the file's
top-level ``controller`` key and dispatches by name to the module that runs it:

* ``pd``, ``lqr``        -> :mod:`experiments.attitude_rw`
* ``energy``, ``euler``  -> :mod:`experiments.attitude_cmg`
* ``game``               -> :mod:`experiments.attitude_gyrostat`

Modules are imported lazily; one that is not importable yet gives the one-line
error "controller X is not available" (exit status 2).
"""

from __future__ import annotations

import argparse
import importlib
from typing import Any

from experiments.errors import InputError
from experiments.schema import load_toml

#: controller name -> module exposing run(source, scenario, controller, noise, runs, seed)
DISPATCH = {
    "pd": "experiments.attitude_rw",
    "lqr": "experiments.attitude_rw",
    "energy": "experiments.attitude_cmg",
    "euler": "experiments.attitude_cmg",
    "game": "experiments.attitude_gyrostat",
}
NOISES = ("none", "random", "game")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", help="scenario TOML file (data/scenarios/*.toml)")
    parser.add_argument("--controller", default=None, help="one of " + ", ".join(DISPATCH))
    parser.add_argument("--noise", default="none", help="none | random | game (default none)")
    parser.add_argument("--runs", type=int, default=1, help="number of runs (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="root seed (default 0)")


def resolve_module(controller: str) -> Any:
    """Import the module running ``controller`` (InputError if unknown or not available)."""
    if controller not in DISPATCH:
        raise InputError(f"unknown controller '{controller}' (allowed: {', '.join(DISPATCH)})")
    name = DISPATCH[controller]
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name != name:
            raise
        raise InputError(f"controller {controller} is not available") from None


def run(args: argparse.Namespace) -> dict[str, Any]:
    scenario = load_toml(args.scenario)
    controller = args.controller if args.controller is not None else scenario.get("controller")
    if controller is None:
        raise InputError(f"{args.scenario}: no --controller and no top-level 'controller' key")
    if not isinstance(controller, str):
        raise InputError(f"{args.scenario}: field 'controller' must be a string")
    if args.noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{args.noise}'")
    if args.runs < 1:
        raise InputError(f"--runs must be an integer >= 1, got {args.runs}")
    if args.seed < 0:
        raise InputError(f"--seed must be a non-negative integer, got {args.seed}")
    module = resolve_module(controller)
    return module.run(args.scenario, scenario, controller, args.noise, args.runs, args.seed)
