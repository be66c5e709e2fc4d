"""The reaction-wheel scenarios as typed tables: controllers ``pd`` (docs/models.md §2.2) and
``lqr``
(docs/models.md §2.3), run by :func:`kalman_vs_infoset.experiments.sim.attitude_rw.simulate_runs`.

A scenario has the tables ``[body]`` and ``[simulation]`` (required), ``[wheels]``,
``[maneuver]``, ``[noise]`` (defaults) and the controller's own ``[pd]`` or ``[lqr]``
(required by the controller that is run: :meth:`RwScenario.law_table`), plus the
top-level ``name``, ``description``, ``controller`` and ``estimator``. Every field is
declared once (type, bounds, default, unit in its name, one-line doc); unknown keys
are refused and a bad value raises ``pydantic.ValidationError`` (a ``ValueError``),
which :mod:`experiments.scenario` turns into one line naming the file and the field.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, overload

import numpy as np
from kalman_vs_infoset.experiments.sim.estimator_tables import AttitudeEstimatorTables
from kalman_vs_infoset.experiments.sim.fields import (
    Inertia,
    Table,
    Vector3,
    Vector4,
    Vector6,
    field,
    float_bounds,
    int_bounds,
)
from pydantic import model_validator

#: most control steps (and RK4 steps) a run may take: the loop keeps the trajectory
MAX_STEPS = 100_000

_POS = Annotated[float, float_bounds(0.0, open_lo=True)]


class BodyTable(Table):
    """The rigid body: ``J = W diag(J_diag) W^T``."""

    inertia_kgm2: Vector3[Inertia] = field(..., "principal moments of inertia J_diag, kg m^2")
    axes_rotvec_deg: Vector3[Annotated[float, float_bounds(-360.0, 360.0)]] = field(
        (0.0, 0.0, 0.0), "rotation vector of the principal axes W in the body frame, deg"
    )


class WheelsTable(Table):
    """Reaction-wheel limits per axis (none by default)."""

    torque_max_Nm: _POS = field(math.inf, "wheel torque limit per axis, N m")
    momentum_max_Nms: _POS = field(math.inf, "wheel momentum limit per axis, N m s")


class ManeuverTable(Table):
    """The turn: from ``q_target (x) rotation(angle_deg about axis)`` to the target at rest,
    or from random attitudes and rates."""

    axis: Vector3[Annotated[float, float_bounds(-1e9, 1e9)]] = field(
        (0.0, 0.0, 1.0), "turn axis (any non-zero length)"
    )
    angle_deg: Annotated[float, float_bounds(0.0, 180.0)] = field(
        0.0, "turn angle about the axis, deg"
    )
    initial_rate_degps: Vector3[Annotated[float, float_bounds(-100.0, 100.0)]] = field(
        (0.0, 0.0, 0.0), "initial body rate, deg/s"
    )
    target_quaternion: Vector4[Annotated[float, float_bounds(-1.0, 1.0)]] = field(
        (0.0, 0.0, 0.0, 1.0), "target attitude, unit quaternion (x, y, z, w)"
    )
    random_attitude: bool = field(False, "a uniform random initial attitude per run")
    random_rate_degps: Annotated[float, float_bounds(0.0, 100.0)] = field(
        0.0, "uniform random addition to each initial rate component, bound in deg/s"
    )

    @model_validator(mode="after")
    def _directions(self) -> ManeuverTable:
        if np.linalg.norm(self.axis) == 0:
            raise ValueError("field 'maneuver.axis' must be a non-zero vector")
        if abs(np.linalg.norm(self.target_quaternion) - 1.0) > 1e-6:
            raise ValueError("field 'maneuver.target_quaternion' must be a unit quaternion")
        return self


class SimulationTable(Table):
    """Time span, sampling and the settle criterion."""

    duration_s: Annotated[float, float_bounds(1.0, 1e5)] = field(..., "simulated time, s")
    control_period_s: Annotated[float, float_bounds(1e-4, 1.0)] = field(
        0.05, "control period (torque held), s"
    )
    substeps: Annotated[int, int_bounds(1, 100)] = field(1, "RK4 steps per control period")
    settle_angle_deg: _POS = field(0.01, "settled: attitude error below this from then on, deg")
    settle_rate_degps: _POS = field(0.01, "settled: rate below this from then on, deg/s")

    @property
    def steps(self) -> int:
        """Control steps of a run."""
        return int(round(self.duration_s / self.control_period_s))

    @model_validator(mode="after")
    def _bounded(self) -> SimulationTable:
        if self.steps * self.substeps > MAX_STEPS:
            raise ValueError(
                f"field 'simulation.duration_s' {self.duration_s} s at "
                f"'simulation.control_period_s' {self.control_period_s} s x {self.substeps} "
                f"substeps is {self.steps * self.substeps} steps a run; the limit is {MAX_STEPS}"
            )
        return self


class PdTable(Table):
    """The quaternion PD law (seed 001)."""

    k_q: _POS = field(..., "attitude gain k_q, 1/s^2")
    k_w: _POS = field(..., "rate gain k_w, 1/s")
    quaternion_term: Literal["vector", "twice"] = field(
        "vector", "k_q multiplies the error quaternion's vector part, or twice it"
    )


class LqrTable(Table):
    """The LQR law with the analytic Riccati solution (seed 002)."""

    q: Vector6[_POS] = field(..., "diagonal of Q: rate weights q1..q3, attitude q4..q6")
    r: Vector3[_POS] = field(..., "diagonal of R: control weights")
    enforce_constraint: bool = field(
        True, "complete the intermediate-axis attitude weight so that constraint (*) holds"
    )
    shortest: bool = field(False, "flip the error quaternion to a non-negative scalar part")


class NoiseTable(Table):
    """Measurement errors and disturbance (used with ``--noise random`` and ``game``)."""

    meas_angle_deg: Annotated[float, float_bounds(0.0, 10.0)] = field(
        0.002, "attitude error 1-sigma per axis (uniform within +-sqrt(3) sigma), deg"
    )
    meas_rate_degps: Annotated[float, float_bounds(0.0, 10.0)] = field(
        0.0005, "rate error 1-sigma per axis (uniform within +-sqrt(3) sigma), deg/s"
    )
    disturbance_Nm: Annotated[float, float_bounds(0.0, 10.0)] = field(
        0.0, "disturbance torque bound per axis, N m"
    )


class RwScenario(AttitudeEstimatorTables):
    """A validated reaction-wheel scenario (every table with its defaults)."""

    name: str = field("", "scenario name; names the result files")
    description: str = field("", "one line")
    controller: Literal["pd", "lqr"] | None = field(None, "controller (--controller wins)")
    estimator: str | None = field(None, "attitude estimator(s) (--estimators wins)")
    body: BodyTable = field(..., "the rigid body")
    wheels: WheelsTable = field(WheelsTable(), "wheel limits")
    maneuver: ManeuverTable = field(ManeuverTable(), "the turn or the random initial states")
    simulation: SimulationTable = field(..., "time span, sampling, settle criterion")
    pd: PdTable | None = field(None, "quaternion PD gains (controller pd)")
    lqr: LqrTable | None = field(None, "LQR weights (controller lqr)")
    noise: NoiseTable = field(NoiseTable(), "measurement errors, disturbance bound")

    # overloads: a literal controller name gives its table's own type
    @overload
    def law_table(self, controller: Literal["pd"]) -> PdTable: ...
    @overload
    def law_table(self, controller: Literal["lqr"]) -> LqrTable: ...
    @overload
    def law_table(self, controller: str) -> PdTable | LqrTable: ...
    def law_table(self, controller: str) -> PdTable | LqrTable:
        """The table of ``controller`` (``ValueError`` if the scenario has none)."""
        if controller not in ("pd", "lqr"):
            raise ValueError(f"controller '{controller}' is not handled here (use pd or lqr)")
        table = getattr(self, controller)
        if table is None:
            raise ValueError(f"missing table '[{controller}]' (controller {controller} needs it)")
        return table
