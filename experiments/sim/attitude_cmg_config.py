"""The Resurs-P turn with six gyrodines (seed 000, docs/models.md §2.1) as typed tables: controllers
``energy`` and ``euler``, run by :func:`experiments.sim.attitude_cmg.simulate_turn`.

A scenario has top-level keys (the turn: step, times, initial error, tolerances) and
the tables ``[energy]`` (the energy-saving law), ``[euler]`` (the Euler-axis flight
baseline), ``[cmg]`` (the gyrodine cluster) and ``[noise]``; every one has defaults
(the seed's values). Every field is declared once (type, bounds, default, unit in its
name, one-line doc); unknown keys are refused and a bad value raises
``pydantic.ValidationError`` (a ``ValueError``), which :mod:`experiments.scenario` turns
into one line naming the file and the field. The loop's input is the
:class:`kalman_vs_infoset.experiments.sim.turn_setup.TurnSetup` built from it.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from kalman_vs_infoset.experiments.sim.estimator_tables import AttitudeEstimatorTables
from kalman_vs_infoset.experiments.sim.fields import (
    Table,
    Vector2,
    Vector3,
    Vector6,
    field,
    float_bounds,
)
from kalman_vs_infoset.guidance.attitude.cmg import RESURS_P_BETA0_DEG
from kalman_vs_infoset.guidance.attitude.energy import INERTIA_SIGN_READINGS
from pydantic import BeforeValidator, model_validator

#: most steps a turn may take (the loop keeps its histories)
MAX_STEPS = 100_000

_POS = Annotated[float, float_bounds(0.0, open_lo=True)]
_VAR = Vector6[Annotated[float, float_bounds(0.0, 1e6)]]
_GROWTH = Vector2[Annotated[float, float_bounds(0.0, 1.0)]]


def _sign_reading(value: Any) -> Any:
    """A named reading of the products' signs or three signs (one clear message else)."""
    if isinstance(value, str) and value in INERTIA_SIGN_READINGS:
        return value
    if isinstance(value, list | tuple) and len(value) == 3:
        if all(type(v) is int and v in (-1, 1) for v in value):
            return tuple(value)
    raise ValueError("or the signs [s12, s13, s23] of J12, J13, J23, each +1 or -1")


_SIGN_READING = Annotated[
    Literal["standard", "entries"] | tuple[int, int, int], BeforeValidator(_sign_reading)
]


class EnergyTable(Table):
    """The energy-saving discrete law (seed sections 2 and 4)."""

    u0_Nm: Vector3[Annotated[float, float_bounds(-1e4, 1e4)]] = field(
        (0.0, 0.0, 0.0), "initial control U0, N m"
    )
    f1: _GROWTH = field((2.5e-5, 5e-3), "[f1_0, growth]: f1_i = f1_0 (1 + growth i)")
    f2: _GROWTH = field((0.01, 2.5e-4), "[f2_0, growth]: f2_i = f2_0 (1 + growth i)")
    state_var: _VAR = field(
        (1.0, 1.0, 1.0, 0.01, 0.01, 0.01), "diagonal of K_X, rad^2 and (rad/s)^2"
    )
    aux_var: _VAR = field(
        (1.0, 1.0, 1.0, 0.01, 0.01, 0.01), "diagonal of K_xi, rad^2 and (rad/s)^2"
    )
    control_std0_Nm: Annotated[float, float_bounds(0.0, 1e7, open_lo=True)] = field(
        5000.0, "initial control standard deviation (K_U0 = std0^2 E), N m"
    )


class EulerTable(Table):
    """The Euler-axis flight turn (the baseline). The seed gives no phase durations and no
    rule for them: the default durations are calibrated to the seed's index, not derived."""

    accel_time_s: _POS = field(
        5.7,
        "each of the acceleration and deceleration phases, s; calibrated (the seed gives "
        "none): chosen so that the turn's Z is near the seed's 11200 N^2 m^2 s",
    )
    jerk_time_s: Annotated[float, float_bounds(0.0)] = field(
        2.0, "each linear ramp of the acceleration, s"
    )
    natural_freq_radps: Annotated[float, float_bounds(0.0, 10.0, open_lo=True)] = field(
        0.1, "natural frequency of the PD tracking the reference, rad/s"
    )
    damping: Annotated[float, float_bounds(0.0, 10.0, open_lo=True)] = field(
        0.9, "damping ratio of that PD"
    )


class CmgTable(Table):
    """The cluster of six gyrodines (three pairs; seed section 4)."""

    rotor_momentum_Nms: Annotated[float, float_bounds(0.0, 1e5, open_lo=True)] = field(
        250.0, "angular momentum of each rotor, N m s"
    )
    cone_half_angle_deg: Annotated[float, float_bounds(0.0, 90.0, open_lo=True, open_hi=True)] = (
        field(30.0, "half-angle of the precession axes' cone, deg")
    )
    pair_azimuths_deg: Vector3[Annotated[float, float_bounds(-360.0, 360.0)]] = field(
        (0.0, 120.0, 240.0), "azimuths of the three pairs, deg"
    )
    beta0_deg: Vector6[Annotated[float, float_bounds(-720.0, 720.0)]] = field(
        RESURS_P_BETA0_DEG, "initial precession angles, deg"
    )
    sr_threshold: Annotated[float, float_bounds(0.0, 1.0, open_lo=True, open_hi=True)] = field(
        0.05, "normalised manipulability below which the SR inverse is used"
    )
    sr_damping: _POS = field(0.01, "damping of the SR inverse")


class NoiseTable(Table):
    """Measurement errors and disturbances (``--noise random`` and ``game``)."""

    angle_std_rad: Annotated[float, float_bounds(0.0, 1.0)] = field(
        3e-4, "attitude error standard deviation, rad"
    )
    rate_std_radps: Annotated[float, float_bounds(0.0, 1.0)] = field(
        7e-6, "rate error standard deviation, rad/s"
    )
    disturbance_std_Nm: Annotated[float, float_bounds(0.0, 1e3)] = field(
        0.0, "white disturbance torque per step, standard deviation, N m"
    )
    game_disturbance_Nm: Annotated[float, float_bounds(0.0, 1e3)] = field(
        0.0, "--noise game: bound of the torque opposing the control, N m (0: not defined)"
    )


class CmgScenario(AttitudeEstimatorTables):
    """A validated Resurs-P scenario (every table with its defaults)."""

    name: str = field("", "scenario name; names the result files (default resurs_p)")
    description: str = field("", "one line")
    controller: Literal["energy", "euler"] = field("energy", "controller (--controller wins)")
    estimator: str | None = field(None, "attitude estimator(s) (--estimators wins)")
    dt_s: Annotated[float, float_bounds(1e-3, 1.0)] = field(0.1, "step of the law and the plant, s")
    duration_s: Annotated[float, float_bounds(1.0, 1e4)] = field(
        300.0, "turn time (energy index and final errors), s"
    )
    horizon_s: Annotated[float, float_bounds(1.0, 1e4)] = field(360.0, "simulated time, s")
    initial_error_deg: Vector3[Annotated[float, float_bounds(-179.0, 179.0)]] = field(
        (110.0, 45.0, 45.0), "rotation vector of the body relative to the target, deg"
    )
    inertia_products_sign: _SIGN_READING = field(
        "standard",
        "signs of the products of inertia, lost in the print: 'standard' (J_jk = -I_jk, "
        "all '-'), 'entries' (the printed numbers are the entries, all '+') or the signs "
        "[s12, s13, s23] of the entries J12, J13, J23",
    )
    angle_tol_deg: _POS = field(0.2, "settled: attitude error below this, deg")
    rate_tol_degps: _POS = field(0.02, "settled: rate below this, deg/s")
    energy: EnergyTable = field(EnergyTable(), "the energy-saving law")
    euler: EulerTable = field(EulerTable(), "the Euler-axis flight turn")
    cmg: CmgTable = field(CmgTable(), "the gyrodine cluster")
    noise: NoiseTable = field(NoiseTable(), "measurement errors, disturbances")

    @property
    def n_steps(self) -> int:
        """Steps of a run (to the horizon)."""
        return int(round(self.horizon_s / self.dt_s))

    @model_validator(mode="after")
    def _consistent(self) -> CmgScenario:
        eu = self.euler
        if self.horizon_s < self.duration_s:
            raise ValueError("field 'horizon_s' must be >= duration_s")
        if not 0 < eu.accel_time_s <= self.duration_s / 2:
            raise ValueError("field 'euler.accel_time_s' must be in (0, duration_s/2]")
        if not eu.jerk_time_s <= eu.accel_time_s / 2:
            raise ValueError("field 'euler.jerk_time_s' must be in [0, accel_time_s/2]")
        # the law takes its square (a variance), which a positive value can underflow
        if self.energy.control_std0_Nm**2 <= 0.0:
            raise ValueError(
                f"field 'energy.control_std0_Nm' = {self.energy.control_std0_Nm:g} N m "
                "squares to 0; give at least 1e-150"
            )
        if self.n_steps > MAX_STEPS:
            raise ValueError(
                f"field 'horizon_s' {self.horizon_s} s at 'dt_s' {self.dt_s} s is "
                f"{self.n_steps} steps a run; the limit is {MAX_STEPS}"
            )
        return self
