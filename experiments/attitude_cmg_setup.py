"""Resurs-P scenario (seed 000, SPEC 2.1): validation of the TOML tables into a
:class:`~experiments.sim.turn_setup.TurnSetup`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from experiments.errors import InputError
from experiments.schema import Choice, Num, Str, Vec, validate_table
from experiments.sim.turn_setup import SQRT3, TurnSetup  # noqa: F401 - re-exported
from guidance.attitude.cmg import RESURS_P_BETA0_DEG, CmgCluster
from guidance.attitude.energy import EnergySavingConfig, resurs_p_inertia

CONTROLLERS = ("energy", "euler")

_POS = Num(0.0, open_lo=True)
_TABLES = ("energy", "euler", "cmg", "noise")
_TOP_RULES = {
    "controller": Choice(CONTROLLERS),
    "name": Str(),
    "description": Str(),
    "dt_s": Num(1e-3, 1.0),
    "duration_s": Num(1.0, 1e4),
    "horizon_s": Num(1.0, 1e4),
    "initial_error_deg": Vec(Num(-179.0, 179.0), 3),
    "inertia_product_signs": Vec(Num(-1, 1, integer=True), 3),
    "angle_tol_deg": _POS,
    "rate_tol_degps": _POS,
}
_TOP_DEFAULTS = {
    "controller": "energy",
    "name": "",
    "description": "",
    "dt_s": 0.1,
    "duration_s": 300.0,
    "horizon_s": 360.0,
    "initial_error_deg": (110.0, 45.0, 45.0),
    "inertia_product_signs": (1, 1, 1),
    "angle_tol_deg": 0.2,
    "rate_tol_degps": 0.02,
}
_ENERGY_RULES = {
    "u0_Nm": Vec(Num(-1e4, 1e4), 3),
    "f1": Vec(Num(0.0, 1.0), 2),
    "f2": Vec(Num(0.0, 1.0), 2),
    "state_var": Vec(Num(0.0, 1e6), 6),
    "aux_var": Vec(Num(0.0, 1e6), 6),
    "control_std0_Nm": Num(0.0, 1e7, open_lo=True),
}
_ENERGY_DEFAULTS = {
    "u0_Nm": (0.0, 0.0, 0.0),
    "f1": (2.5e-5, 5e-3),
    "f2": (0.01, 2.5e-4),
    "state_var": (1.0, 1.0, 1.0, 0.01, 0.01, 0.01),
    "aux_var": (1.0, 1.0, 1.0, 0.01, 0.01, 0.01),
    "control_std0_Nm": 5000.0,
}
_EULER_RULES = {
    "accel_time_s": _POS,
    "jerk_time_s": Num(0.0),
    "natural_freq_radps": Num(0.0, 10.0, open_lo=True),
    "damping": Num(0.0, 10.0, open_lo=True),
}
_EULER_DEFAULTS = {
    "accel_time_s": 6.0,
    "jerk_time_s": 2.0,
    "natural_freq_radps": 0.1,
    "damping": 0.9,
}
_CMG_RULES = {
    "rotor_momentum_Nms": Num(0.0, 1e5, open_lo=True),
    "cone_half_angle_deg": Num(0.0, 90.0, open_lo=True, open_hi=True),
    "pair_azimuths_deg": Vec(Num(-360.0, 360.0), 3),
    "beta0_deg": Vec(Num(-720.0, 720.0), 6),
    "sr_threshold": Num(0.0, 1.0, open_lo=True, open_hi=True),
    "sr_damping": _POS,
}
_CMG_DEFAULTS = {
    "rotor_momentum_Nms": 250.0,
    "cone_half_angle_deg": 30.0,
    "pair_azimuths_deg": (0.0, 120.0, 240.0),
    "beta0_deg": RESURS_P_BETA0_DEG,
    "sr_threshold": 0.05,
    "sr_damping": 0.01,
}
_NOISE_RULES = {
    "angle_std_rad": Num(0.0, 1.0),
    "rate_std_radps": Num(0.0, 1.0),
    "disturbance_std_Nm": Num(0.0, 1e3),
    "game_disturbance_Nm": Num(0.0, 1e3),
}
_NOISE_DEFAULTS = {
    "angle_std_rad": 3e-4,
    "rate_std_radps": 7e-6,
    "disturbance_std_Nm": 0.0,
    "game_disturbance_Nm": 0.0,
}


def _table(source: str, scenario: Mapping[str, Any], key: str, rules, defaults) -> dict:
    return validate_table(source, scenario.get(key, {}), rules, defaults, prefix=f"{key}.")


def setup_from_scenario(source: str, scenario: Mapping[str, Any]) -> TurnSetup:
    """Validate a scenario dict (unknown keys and bad values raise InputError)."""
    flat = {k: v for k, v in scenario.items() if k not in _TABLES}
    top = validate_table(source, flat, _TOP_RULES, _TOP_DEFAULTS)
    en = _table(source, scenario, "energy", _ENERGY_RULES, _ENERGY_DEFAULTS)
    eu = _table(source, scenario, "euler", _EULER_RULES, _EULER_DEFAULTS)
    cm = _table(source, scenario, "cmg", _CMG_RULES, _CMG_DEFAULTS)
    no = _table(source, scenario, "noise", _NOISE_RULES, _NOISE_DEFAULTS)
    if top["horizon_s"] < top["duration_s"]:
        raise InputError(f"{source}: field 'horizon_s' must be >= duration_s")
    if any(s == 0 for s in top["inertia_product_signs"]):
        raise InputError(f"{source}: field 'inertia_product_signs' must be +1 or -1 each")
    if not 0 < eu["accel_time_s"] <= top["duration_s"] / 2:
        raise InputError(f"{source}: field 'euler.accel_time_s' must be in (0, duration_s/2]")
    if not eu["jerk_time_s"] <= eu["accel_time_s"] / 2:
        raise InputError(f"{source}: field 'euler.jerk_time_s' must be in [0, accel_time_s/2]")
    meas_var = (no["angle_std_rad"] ** 2,) * 3 + (no["rate_std_radps"] ** 2,) * 3
    energy = EnergySavingConfig(
        dt_s=top["dt_s"],
        f1_0=en["f1"][0],
        f1_growth=en["f1"][1],
        f2_0=en["f2"][0],
        f2_growth=en["f2"][1],
        state_var=en["state_var"],
        aux_var=en["aux_var"],
        meas_var=meas_var,
        control_var0_N2m2=en["control_std0_Nm"] ** 2,
        u0_Nm=en["u0_Nm"],
    )
    cluster = CmgCluster(
        cm["rotor_momentum_Nms"],
        cm["cone_half_angle_deg"],
        tuple(cm["pair_azimuths_deg"]),
        cm["sr_threshold"],
        cm["sr_damping"],
    )
    return TurnSetup(
        inertia_kgm2=resurs_p_inertia(top["inertia_product_signs"]),
        initial_error_rad=np.radians(top["initial_error_deg"]),
        dt_s=top["dt_s"],
        duration_s=top["duration_s"],
        horizon_s=top["horizon_s"],
        energy=energy,
        euler=eu,
        cluster=cluster,
        beta0_rad=np.radians(cm["beta0_deg"]),
        angle_std_rad=no["angle_std_rad"],
        rate_std_radps=no["rate_std_radps"],
        disturbance_std_Nm=no["disturbance_std_Nm"],
        angle_tol_deg=top["angle_tol_deg"],
        rate_tol_degps=top["rate_tol_degps"],
        game_disturbance_Nm=no["game_disturbance_Nm"],
        name=str(scenario.get("name") or top["name"] or "resurs_p"),
    )
