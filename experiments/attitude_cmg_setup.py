"""Resurs-P scenario (seed 000, docs/models.md §2.1): a scenario's tables read into the typed
:class:`~kalman_vs_infoset.experiments.sim.attitude_cmg_config.CmgScenario` and the
:class:`~kalman_vs_infoset.experiments.sim.turn_setup.TurnSetup` of the loop."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import validate
from kalman_vs_infoset.experiments.sim.attitude_cmg_config import CmgScenario
from kalman_vs_infoset.experiments.sim.turn_setup import SQRT3, TurnSetup  # noqa: F401 - re-exported


def parse_scenario(source: str, scenario: Mapping[str, Any]) -> CmgScenario:
    """The typed scenario (``InputError`` of one line naming ``source`` and the field)."""
    return validate(CmgScenario, dict(scenario), source)


def setup_from_scenario(source: str, scenario: Mapping[str, Any]) -> TurnSetup:
    """The turn of a scenario's tables (unknown keys and bad values raise ``InputError``)."""
    config = parse_scenario(source, scenario)
    try:
        return TurnSetup.from_config(config)
    except ValueError as exc:  # the library's own checks, as the other loops report them
        raise InputError(f"{source}: {exc}") from None
