"""Intercept scenarios (TOML, SPEC 1.8 and 3): reading, validating, resolving.

A scenario file has the tables ``[model]``, ``[estimator]`` (the a-priori boxes B
and D known to the estimators), ``[truth]`` (the boxes the true initial state is
drawn from, uniformly; a degenerate interval fixes a value), ``[range_finder]``,
``[guidance]``, ``[experiment]``, an optional ``[reference]`` of the paper's
numbers and an optional ``[attitude]`` loop holding the spacecraft's axis (the
end-to-end scenario, validated by :class:`experiments.pointing_loop.PointingLoop`).
Every field is checked; unknown keys are errors.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from experiments.errors import InputError
from experiments.noise import NOISES
from experiments.schema import (
    Bool,
    Choice,
    Interval,
    Num,
    Str,
    apply_overrides,
    load_toml,
    override_suffix,
    validate_table,
)

POS = Num(0.0, open_lo=True)
NONNEG = Num(0.0)

MODEL_RULES = {
    "closing_speed_kmps": Num(1.0, 100.0),
    "nu_mps2": Num(0.0, 1.0),
    "bearing_bound_start_rad": Num(1e-7, 0.1),
    "bearing_bound_end_rad": Num(1e-7, 0.1),
    "nominal_range_km": Num(10.0, 1e6),
    "eps_km": Num(0.1, 1000.0),
    "dt_s": Num(0.01, 60.0),
    "sun_distance_km": Num(1e6, 1e10),
}
ESTIMATOR_RULES = {
    "y_km": Interval(Num(-1e4, 1e4)),
    "z_km": Interval(Num(-1e4, 1e4)),
    "x_km": Interval(Num(1.0, 1e6)),
    "vy_kmps": Interval(Num(-10.0, 10.0)),
    "vz_kmps": Interval(Num(-10.0, 10.0)),
    "vx_kmps": Interval(Num(-100.0, -0.1)),
    "n_sections": Num(2, 400, integer=True),
    "sections": Choice(("nodes", "slabs", "points")),
    # slabs: bound the kinematic term the linear model neglects (estim.infoset)
    "kinematic_margin": Bool(),
    # slabs: split a slab wider than x_hi/x_lo = split_ratio before each prediction
    # (1e6 turns splitting off in practice)
    "split_ratio": Num(1.0, 1e6, open_lo=True),
    "closing_speed_kmps": Interval(Num(0.1, 100.0)),
    "kalman_sigma": Num(0.5, 10.0),
    # EKF/UKF: project the range estimate onto [x_lo - e_hi t, x_hi - e_lo t]
    "kalman_range_constraint": Bool(),
    # EKF/UKF: factor on every noise variance (1: uniform errors; 3: the largest
    # variance of an error within its bound)
    "kalman_noise_inflation": Num(1.0, 1e6),
}
# the truth's table holds the a-priori boxes only (an allow-list: new estimator
# options need no entry here)
TRUTH_RULES = {
    k: ESTIMATOR_RULES[k] for k in ("y_km", "z_km", "x_km", "vy_kmps", "vz_kmps", "vx_kmps")
}
RANGE_RULES = {
    "enabled": Bool(),
    "rel_bound": Num(0.0, 0.5, open_lo=True),
    "first_s": Num(0.0, 1e4),
    "period_s": Num(0.01, 1e4),
}
GUIDANCE_RULES = {
    "lateral": Bool(),
    "vertical": Bool(),
    "reserve_mps": Num(0.0, 1e5),
    "min_impulse_mps": Num(0.0, 1e3),
    "max_impulse_mps": Num(0.0, 1e3, open_lo=True),
}
EXPERIMENT_RULES = {
    "runs": Num(1, 10**7, integer=True),
    "seed": Num(0, 2**63 - 1, integer=True),
    "noise": Choice(NOISES),
    "estimator": Choice(("infoset", "ekf", "ukf")),
}
REFERENCE_RULES = {
    "miss_random_m": NONNEG,
    "fuel_random_mps": NONNEG,
    "miss_game_m": NONNEG,
    "fuel_game_mps": NONNEG,
    "source": Str(),
}
TOP_RULES = {
    "name": Str(),
    "description": Str(),
    "model": None,
    "estimator": None,
    "truth": None,
    "range_finder": None,
    "guidance": None,
    "experiment": None,
    "reference": None,
    "attitude": None,
}

DEFAULTS = {
    "model": {
        "closing_speed_kmps": 58.0,
        "nu_mps2": 0.005,
        "bearing_bound_start_rad": 1.5e-4,
        "bearing_bound_end_rad": 2.3e-4,
        "nominal_range_km": 5801.3,
        "eps_km": 5.0,
        "dt_s": 0.5,
        "sun_distance_km": 1.496e8,
    },
    "estimator": {
        "y_km": (-10.0, 10.0),
        "z_km": (-10.0, 10.0),
        "x_km": (5301.3, 6301.3),
        "vy_kmps": (-0.1, 0.1),
        "vz_kmps": (-0.1, 0.1),
        "vx_kmps": (-59.0, -57.0),
        "n_sections": 29,
        "sections": "nodes",
        "kinematic_margin": True,
        "split_ratio": 1.5,
        "closing_speed_kmps": None,  # filled in: [e, e], the seed's known closing speed
        "kalman_sigma": 3.0,
        "kalman_range_constraint": False,
        "kalman_noise_inflation": 1.0,
    },
    "range_finder": {"enabled": False, "rel_bound": 0.05, "first_s": 1.0, "period_s": 2.0},
    "guidance": {
        "lateral": True,
        "vertical": True,
        "reserve_mps": 2000.0,
        "min_impulse_mps": 0.25,
        "max_impulse_mps": 7.5,
    },
    "experiment": {"runs": 1, "seed": 1, "noise": "random", "estimator": "infoset"},
    "reference": {},
}


@dataclass(frozen=True)
class InterceptScenario:
    """A resolved, validated intercept scenario (all tables with defaults filled in)."""

    name: str
    description: str
    model: dict[str, Any]
    estimator: dict[str, Any]
    truth: dict[str, Any]
    range_finder: dict[str, Any]
    guidance: dict[str, Any]
    experiment: dict[str, Any]
    reference: dict[str, Any]
    source: str = ""
    attitude: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _contained(source: str, inner: tuple, outer: tuple, field: str) -> None:
    if inner[0] < outer[0] or inner[1] > outer[1]:
        raise InputError(
            f"{source}: field 'truth.{field}' {list(inner)} must lie inside "
            f"'estimator.{field}' {list(outer)} (the a-priori box must contain the truth)"
        )


def parse_scenario(data: dict[str, Any], source: str = "<scenario>") -> InterceptScenario:
    """Validate a scenario dict (as read from TOML)."""
    unknown = sorted(set(data) - set(TOP_RULES))
    if unknown:
        raise InputError(
            f"{source}: unknown key '{unknown[0]}' (allowed: {', '.join(sorted(TOP_RULES))})"
        )
    for key in ("name", "description"):
        if key in data and not isinstance(data[key], str):
            raise InputError(f"{source}: field '{key}' must be a string")
    tables = {}
    for key, rules in (
        ("model", MODEL_RULES),
        ("estimator", ESTIMATOR_RULES),
        ("range_finder", RANGE_RULES),
        ("guidance", GUIDANCE_RULES),
        ("experiment", EXPERIMENT_RULES),
        ("reference", REFERENCE_RULES),
    ):
        tables[key] = validate_table(source, data.get(key, {}), rules, DEFAULTS[key], key + ".")
    est = tables["estimator"]
    if est["closing_speed_kmps"] is None:
        est["closing_speed_kmps"] = (tables["model"]["closing_speed_kmps"],) * 2
    truth_defaults = {k: est[k] for k in TRUTH_RULES}
    tables["truth"] = validate_table(
        source, data.get("truth", {}), TRUTH_RULES, truth_defaults, "truth."
    )
    for f in TRUTH_RULES:
        _contained(source, tables["truth"][f], tables["estimator"][f], f)
    if est["kalman_range_constraint"]:
        # the constraint's interval moves at the closing-speed interval's speeds: it
        # holds the truth only if every true closing speed -vx lies in that interval
        closing = tuple(sorted(-v for v in tables["truth"]["vx_kmps"]))
        lo, hi = est["closing_speed_kmps"]
        if closing[0] < lo or closing[1] > hi:
            raise InputError(
                f"{source}: field 'estimator.closing_speed_kmps' {[lo, hi]} must contain "
                f"the truth's closing speeds -truth.vx_kmps {list(closing)} when "
                f"'estimator.kalman_range_constraint' is true (the interval must hold the truth)"
            )
    m, g = tables["model"], tables["guidance"]
    if g["min_impulse_mps"] > g["max_impulse_mps"]:
        raise InputError(f"{source}: field 'guidance.min_impulse_mps' must be <= max_impulse_mps")
    if not (g["lateral"] or g["vertical"]):
        raise InputError(f"{source}: field 'guidance.lateral' or 'guidance.vertical' must be true")
    if m["bearing_bound_start_rad"] > m["bearing_bound_end_rad"]:
        # the set's bearing strip and the range finder's off-axis bound take the bound
        # at the smallest range: sound only if it grows as the range closes
        raise InputError(
            f"{source}: field 'model.bearing_bound_start_rad' must be <= "
            f"'model.bearing_bound_end_rad' (the bound grows as the range closes)"
        )
    if tables["estimator"]["x_km"][0] <= m["eps_km"]:
        raise InputError(f"{source}: field 'estimator.x_km' must start above 'model.eps_km'")
    attitude = data.get("attitude")
    if attitude is not None:
        # validated by the pointing loop itself (one line, exit 2, at load time)
        import numpy as np

        from experiments.pointing_loop import PointingLoop

        PointingLoop.from_table(str(source), attitude, np.random.default_rng(0))
    return InterceptScenario(
        name=data.get("name", Path(source).stem),
        attitude=attitude,
        description=data.get("description", ""),
        source=str(source),
        **tables,
    )


def load_scenario(path: str | Path, overrides: Sequence[str] = ()) -> InterceptScenario:
    """Read and validate an intercept scenario file, with optional ``TABLE.KEY=VALUE``
    overrides (:func:`~experiments.schema.apply_overrides`; the name gets a
    ``+key=value`` suffix per override)."""
    data = load_toml(path)
    if not overrides:
        return parse_scenario(data, str(path))
    data = apply_overrides(data, overrides)
    data["name"] = str(data.get("name", Path(path).stem)) + override_suffix(overrides)
    return parse_scenario(data, f"{path} (with --set)")
