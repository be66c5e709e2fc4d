"""What one Resurs-P turn needs (seed 000, SPEC 2.1): the typed setup of
:func:`experiments.sim.attitude_cmg.simulate_turn` (built from a scenario by
:func:`experiments.attitude_cmg_setup.setup_from_scenario`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from guidance.attitude.cmg import CmgCluster
from guidance.attitude.energy import EnergySavingConfig
from guidance.attitude.plant import RigidBody

SQRT3 = float(np.sqrt(3.0))


@dataclass(frozen=True)
class TurnSetup:
    """Everything one turn needs (built from a validated scenario)."""

    inertia_kgm2: NDArray[np.float64]
    initial_error_rad: NDArray[np.float64]
    dt_s: float
    duration_s: float
    horizon_s: float
    energy: EnergySavingConfig
    euler: dict[str, float]
    cluster: CmgCluster
    beta0_rad: NDArray[np.float64]
    angle_std_rad: float
    rate_std_radps: float
    disturbance_std_Nm: float
    angle_tol_deg: float = 0.2
    rate_tol_degps: float = 0.02
    game_disturbance_Nm: float = 0.0
    name: str = "resurs_p"
    body: RigidBody = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (0 < self.dt_s and self.duration_s <= self.horizon_s):
            raise ValueError("need dt_s > 0 and duration_s <= horizon_s")
        object.__setattr__(self, "body", RigidBody(self.inertia_kgm2))

    @property
    def n_turn_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    @property
    def n_steps(self) -> int:
        return int(round(self.horizon_s / self.dt_s))
