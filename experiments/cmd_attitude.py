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
import inspect
from pathlib import Path
from typing import Any

from experiments.attitude_est import resolve_estimators, write_outputs
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
    parser.add_argument(
        "--estimator",
        default=None,
        help="perfect | ukf | box, or a comma list run on the same realisations "
        "(default: the scenario's 'estimator', else perfect for --noise none, box otherwise)",
    )
    parser.add_argument(
        "--out", default=None, help="output directory (default: results/attitude/<scenario>)"
    )


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
    default_est = scenario.pop("estimator", None)
    if default_est is not None and not isinstance(default_est, str):
        raise InputError(f"{args.scenario}: field 'estimator' must be a string")
    estimators = resolve_estimators(getattr(args, "estimator", None), default_est, args.noise)
    takes_estimator = "estimator" in inspect.signature(module.run).parameters
    results, rows = [], []
    for est in estimators:
        if takes_estimator:
            res = module.run(
                args.scenario, scenario, controller, args.noise, args.runs, args.seed, est
            )
        elif est == "perfect":
            res = module.run(args.scenario, scenario, controller, args.noise, args.runs, args.seed)
        else:
            raise InputError(f"controller {controller} does not take --estimator {est}")
        for row in res.pop("_rows", []):
            rows.append({"controller": controller, "estimator": est, "noise": args.noise, **row})
        results.append(res)
    result = dict(results[0])
    if len(results) > 1:
        result["rows"] = results
    out = getattr(args, "out", None)
    out_dir = Path(out) if out else Path("results") / "attitude" / Path(args.scenario).stem
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"--out {out_dir}: not a directory")
    if rows:
        stem = f"{Path(args.scenario).stem}-{controller}-{args.noise}-{'_'.join(estimators)}"
        meta = {"scenario": scenario, "controller": controller, "noise": args.noise,
                "estimators": estimators, "runs": args.runs, "seed": args.seed}  # fmt: skip
        result["files"] = write_outputs(out_dir, stem, rows, meta)
    return result
