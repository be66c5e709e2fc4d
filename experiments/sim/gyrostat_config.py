"""The three-rotor gyrostat game turn (seed 004, docs/models.md §2.4) as typed tables, and the setup
of its loop (:func:`kalman_vs_infoset.experiments.sim.gyrostat.simulate_turn`).

A scenario has the tables ``[gyrostat]`` and ``[manoeuvre]`` (required) and
``[simulation]`` (defaults), plus the top-level ``name``, ``description``,
``controller`` and ``estimator``. Every field is declared once (type, bounds, default,
unit in its name, one-line doc); unknown keys are refused and a bad value raises
``pydantic.ValidationError`` (a ``ValueError``), which :mod:`experiments.scenario` turns
into one line naming the file and the field. :meth:`GyrostatSetup.from_config` designs
``a*`` (seed section 3) and builds what a batch of turns needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from kalman_vs_infoset.experiments.sim.estimator_tables import AttitudeEstimatorTables
from kalman_vs_infoset.experiments.sim.fields import (
    Inertia,
    Table,
    Vector3,
    Vector4,
    field,
    float_bounds,
    int_bounds,
)
from kalman_vs_infoset.experiments.sim.gyrostat import LoopConfig
from kalman_vs_infoset.guidance.attitude.game import GameLaw, design_a_star
from kalman_vs_infoset.guidance.attitude.gyrostat import Gyrostat
from pydantic import model_validator

from kalman_vs_infoset.numerics.rotations import error_quaternion, qmul

#: most control steps a run may take
MAX_STEPS = 100_000
#: ``simulation.disturbance = "auto"``: the disturbance kind of each ``--noise``
AUTO_DISTURBANCE = {"none": "none", "random": "random", "game": "adversarial"}

_POS3 = Vector3[Annotated[float, float_bounds(0.0, open_lo=True)]]


class GyrostatTable(Table):
    """The gyrostat, its rotor torque limits and the disturbance bounds (seed 1.1-1.4, 2.5)."""

    A_kgm2: Vector3[Inertia] = field(..., "total principal moments A_i (rotors included), kg m^2")
    rotor_J_kgm2: Vector3[Inertia] = field(..., "rotor axial moments J_i, kg m^2")
    alpha_Nm: _POS3 = field(..., "rotor torque limits |u_i| <= alpha_i, N m")
    beta_Nm: Vector3[Annotated[float, float_bounds(0.0)]] = field(
        ..., "disturbance bounds |v_i| <= beta_i, N m"
    )
    rho: Vector3[Annotated[float, float_bounds(0.0, 1.0, open_lo=True, open_hi=True)]] = field(
        ..., "margins: beta* <= rho_i a*_i"
    )

    @model_validator(mode="after")
    def _buildable(self) -> GyrostatTable:
        try:
            Gyrostat(np.asarray(self.A_kgm2, float), np.asarray(self.rotor_J_kgm2, float))
        except ValueError as exc:
            raise ValueError(f"table 'gyrostat': {exc}") from None
        return self


class ManoeuvreTable(Table):
    """The rest-to-rest turn: ``initial_angle_deg`` about ``initial_axis`` to the target."""

    initial_axis: Vector3[Annotated[float, float_bounds(-1e6, 1e6)]] = field(
        ..., "turn axis, body frame (non-zero)"
    )
    initial_angle_deg: Annotated[float, float_bounds(0.0, 180.0, open_hi=True)] = field(
        ..., "turn angle, deg"
    )
    target_quaternion: Vector4[Annotated[float, float_bounds(-1.0, 1.0)]] = field(
        (0.0, 0.0, 0.0, 1.0), "target attitude, unit quaternion (x, y, z, w)"
    )

    @model_validator(mode="after")
    def _directions(self) -> ManoeuvreTable:
        if np.linalg.norm(self.initial_axis) == 0:
            raise ValueError("field 'manoeuvre.initial_axis' must be a non-zero vector")
        if abs(np.linalg.norm(self.target_quaternion) - 1.0) > 1e-6:
            raise ValueError(
                "field 'manoeuvre.target_quaternion' must be a unit quaternion (x, y, z, w)"
            )
        return self


class SimulationTable(Table):
    """Sampling, horizon, settle criterion, disturbance and measurement errors."""

    control_period_s: Annotated[float, float_bounds(1e-4, 1.0)] = field(
        0.05, "control period (law sampled, ZOH), s"
    )
    substeps: Annotated[int, int_bounds(1, 100)] = field(1, "RK4 steps per control period")
    horizon_factor: Annotated[float, float_bounds(1.0, 10.0, open_lo=True)] = field(
        1.25, "simulated time in units of the guaranteed time tau"
    )
    settle_angle_deg: Annotated[float, float_bounds(0.0, 10.0, open_lo=True)] = field(
        0.05, "settled: attitude error below this from then on, deg"
    )
    settle_rate_degps: Annotated[float, float_bounds(0.0, 10.0, open_lo=True)] = field(
        0.01, "settled: rate below this from then on, deg/s"
    )
    disturbance: Literal["auto", "none", "random", "constant", "adversarial"] = field(
        "auto", "disturbance kind (auto: none/random/adversarial by --noise)"
    )
    switching: Literal["discrete", "sign"] = field(
        "discrete", "exact discrete switching, or the raw sign of psi"
    )
    meas_angle_deg: Annotated[float, float_bounds(0.0, 1.0)] = field(
        0.001, "attitude error bound per axis, deg"
    )
    meas_rate_degps: Annotated[float, float_bounds(0.0, 1.0)] = field(
        0.0001, "rate error bound per axis, deg/s"
    )
    meas_rotor_radps: Annotated[float, float_bounds(0.0, 100.0)] = field(
        0.01, "rotor-rate error bound, rad/s"
    )


class GyrostatScenario(AttitudeEstimatorTables):
    """A validated gyrostat scenario (every table with its defaults)."""

    name: str | None = field(None, "scenario name; names the result files (default: the file)")
    description: str = field("", "one line")
    controller: Literal["game"] | None = field(None, "controller (--controller wins)")
    estimator: str | None = field(None, "attitude estimator(s) (--estimators wins)")
    gyrostat: GyrostatTable = field(..., "the gyrostat and its bounds")
    manoeuvre: ManoeuvreTable = field(..., "the turn")
    simulation: SimulationTable = field(SimulationTable(), "sampling, settle, noise")


def initial_quaternion(man: ManoeuvreTable) -> np.ndarray:
    """``q0 = q_target (x) (sin(theta/2) e, cos(theta/2))``: the turn to do is theta about e."""
    axis = np.asarray(man.initial_axis, float)
    half = 0.5 * np.radians(man.initial_angle_deg)
    rel = np.concatenate([np.sin(half) * axis / np.linalg.norm(axis), [np.cos(half)]])
    return qmul(np.asarray(man.target_quaternion, float), rel)


@dataclass(frozen=True)
class GyrostatSetup:
    """Everything a batch of turns needs (from a validated scenario: :meth:`from_config`)."""

    name: str
    gyro: Gyrostat
    law: GameLaw
    q0: np.ndarray
    q_target: np.ndarray
    alpha_Nm: np.ndarray
    beta_Nm: np.ndarray
    design: Any
    disturbance: str
    cfg: LoopConfig
    switching: str

    @classmethod
    def from_config(cls, config: GyrostatScenario, noise: str, name: str) -> GyrostatSetup:
        """Design ``a*`` and build the loop of ``config`` under ``noise``.

        Parameters
        ----------
        config : GyrostatScenario
            The validated tables.
        noise : {"none", "random", "game"}
            Picks the disturbance kind (``auto``) and whether measurements are noisy.
        name : str
            The scenario's name when ``config`` has none.

        Raises
        ------
        ValueError
            The design is infeasible, or the horizon takes more than ``MAX_STEPS`` steps.
        """
        g, man, sim = config.gyrostat, config.manoeuvre, config.simulation
        gyro = Gyrostat(np.asarray(g.A_kgm2, float), np.asarray(g.rotor_J_kgm2, float))
        alpha, beta, rho = (np.asarray(v, float) for v in (g.alpha_Nm, g.beta_Nm, g.rho))
        q_t = np.asarray(man.target_quaternion, float)
        q0 = initial_quaternion(man)
        eta0 = error_quaternion(q0, q_t)[:3]
        try:
            design = design_a_star(gyro, eta0, alpha, beta, rho)
        except ValueError as exc:
            raise ValueError(f"infeasible gyrostat design: {exc}") from None
        kind = AUTO_DISTURBANCE[noise] if sim.disturbance == "auto" else sim.disturbance
        noisy = noise in ("random", "game")
        h = sim.control_period_s
        horizon = max(sim.horizon_factor * design.tau_s, 10 * h)
        if horizon / h * sim.substeps > MAX_STEPS:
            raise ValueError(
                f"field 'simulation.control_period_s' {h} s makes the "
                f"{horizon:.0f}-s horizon {int(horizon / h * sim.substeps)} steps a run; "
                f"the limit is {MAX_STEPS}"
            )
        cfg = LoopConfig(
            period_s=h,
            substeps=sim.substeps,
            horizon_s=horizon,
            settle_angle_rad=np.radians(sim.settle_angle_deg),
            settle_rate_radps=np.radians(sim.settle_rate_degps),
            meas_angle_rad=np.radians(sim.meas_angle_deg) if noisy else 0.0,
            meas_rate_radps=np.radians(sim.meas_rate_degps) if noisy else 0.0,
            meas_rotor_radps=sim.meas_rotor_radps if noisy else 0.0,
            estimator_options=config.estimator_options,
        )
        law = GameLaw(design.a_star, rho, h, mode=sim.switching)
        label = config.name if config.name is not None else name
        return cls(label, gyro, law, q0, q_t, alpha, beta, design, kind, cfg, sim.switching)
