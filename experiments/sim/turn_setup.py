"""What one Resurs-P turn needs (seed 000, docs/models.md §2.1): the typed setup of
:func:`experiments.sim.attitude_cmg.simulate_turn`, in SI units and radians, built from
a typed scenario by :meth:`TurnSetup.from_config`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from kalman_vs_infoset.experiments.sim.attitude_cmg_config import CmgScenario, EulerTable
from kalman_vs_infoset.guidance.attitude.cmg import CmgCluster
from kalman_vs_infoset.guidance.attitude.energy import EnergySavingConfig, resurs_p_inertia
from kalman_vs_infoset.guidance.attitude.plant import RigidBody
from numpy.typing import NDArray

SQRT3 = float(np.sqrt(3.0))


@dataclass(frozen=True)
class TurnSetup:
    """Everything one turn needs (built from a validated scenario: :meth:`from_config`)."""

    inertia_kgm2: NDArray[np.float64]
    initial_error_rad: NDArray[np.float64]
    dt_s: float
    duration_s: float
    horizon_s: float
    energy: EnergySavingConfig
    euler: EulerTable
    cluster: CmgCluster
    beta0_rad: NDArray[np.float64]
    angle_std_rad: float
    rate_std_radps: float
    disturbance_std_Nm: float
    angle_tol_deg: float = 0.2
    rate_tol_degps: float = 0.02
    game_disturbance_Nm: float = 0.0
    name: str = "resurs_p"
    #: the scenario's ``[estimator_options.<name>]`` tables (the loop's estimator takes its own)
    estimator_options: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    body: RigidBody = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (0 < self.dt_s and self.duration_s <= self.horizon_s):
            raise ValueError("need dt_s > 0 and duration_s <= horizon_s")
        object.__setattr__(self, "body", RigidBody(self.inertia_kgm2))

    @classmethod
    def from_config(cls, config: CmgScenario) -> TurnSetup:
        """The turn of a typed scenario (its name, or ``resurs_p`` when empty).

        Parameters
        ----------
        config : CmgScenario
            The validated tables.

        Returns
        -------
        TurnSetup
        """
        en, cm, no = config.energy, config.cmg, config.noise
        meas_var = (no.angle_std_rad**2,) * 3 + (no.rate_std_radps**2,) * 3
        energy = EnergySavingConfig(
            dt_s=config.dt_s,
            f1_0=en.f1[0],
            f1_growth=en.f1[1],
            f2_0=en.f2[0],
            f2_growth=en.f2[1],
            state_var=en.state_var,
            aux_var=en.aux_var,
            meas_var=meas_var,
            control_var0_N2m2=en.control_std0_Nm**2,
            u0_Nm=en.u0_Nm,
        )
        cluster = CmgCluster(
            cm.rotor_momentum_Nms,
            cm.cone_half_angle_deg,
            tuple(cm.pair_azimuths_deg),
            cm.sr_threshold,
            cm.sr_damping,
        )
        return cls(
            inertia_kgm2=resurs_p_inertia(config.inertia_products_sign),
            initial_error_rad=np.radians(config.initial_error_deg),
            dt_s=config.dt_s,
            duration_s=config.duration_s,
            horizon_s=config.horizon_s,
            energy=energy,
            euler=config.euler,
            cluster=cluster,
            beta0_rad=np.radians(cm.beta0_deg),
            angle_std_rad=no.angle_std_rad,
            rate_std_radps=no.rate_std_radps,
            disturbance_std_Nm=no.disturbance_std_Nm,
            angle_tol_deg=config.angle_tol_deg,
            rate_tol_degps=config.rate_tol_degps,
            game_disturbance_Nm=no.game_disturbance_Nm,
            name=config.name or "resurs_p",
            estimator_options=config.estimator_options,
        )

    @property
    def n_turn_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    @property
    def n_steps(self) -> int:
        return int(round(self.horizon_s / self.dt_s))
