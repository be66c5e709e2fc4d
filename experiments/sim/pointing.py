"""Attitude loop holding the longitudinal axis of the interceptor (docs/models.md §2.5, end-to-end).

A simulation of the library layer (:mod:`kalman_vs_infoset.experiments.sim`): it composes a whole
simulated loop (plant, noise, estimator, controller); ``guidance`` keeps the
controllers themselves. Also :class:`PointingCoupling`, the adapter the engagement
uses (formerly ``kalman_vs_infoset.experiments.pointing``).

The spacecraft of Problem A carries reaction wheels; its attitude loop holds the body
axes on the guidance frame (target attitude = identity). The controller (quaternion
PD, docs/models.md §2.2, or LQR, docs/models.md §2.3) reads ``(q, w)`` from an estimator (``box``,
``ukf``,
``perfect`` or any registered attitude estimator, :mod:`estim.registry`) fed by bounded
attitude and rate measurements; the wheel momentum is known on board. Disturbance torques within
``|d_i| <= D``: ``constant`` (drawn once), ``random`` (redrawn every control period)
or ``game`` (``-D sign(M_u)``, opposing the control).

Contract used by the engagement (the lead's integration)::

    loop = PointingLoop.from_config(PointingConfig(...), rng)
    loop.step(dt_s)               # advance by dt_s (whole control periods; a remainder is
                                  # carried to the next call)
    loop.true_error               # Rotation body -> guidance frame (truth)
    loop.estimated_error          # the estimator's centre of that rotation
    loop.knowledge_bound_rad      # box: guaranteed bound of the angle between the two;
                                  # ukf: gate x largest sigma (not guaranteed); perfect:
                                  # the measurement bound |b_a| (the point is a measurement)
    loop.summary()                # max/final pointing error, energy, truth_outside, ...
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Annotated, Any, ClassVar, Literal

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from kalman_vs_infoset.estim.base import PointBelief
from kalman_vs_infoset.estim.intercept.model import BearingBound, ChannelModel, Impulse
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.experiments.sim.estimator_tables import AttitudeEstimatorTables
from kalman_vs_infoset.experiments.sim.fields import Inertia, Vector3, Vector6, float_bounds
from kalman_vs_infoset.experiments.sim.fields import field as declared
from kalman_vs_infoset.guidance.attitude.lqr import LQRController
from kalman_vs_infoset.guidance.attitude.pd import QuaternionPD
from kalman_vs_infoset.guidance.attitude.plant import LoopDiverged, RigidBody, advance_checked
from kalman_vs_infoset.guidance.attitude.wheels import ReactionWheels, rk4_step
from pydantic import model_validator

if TYPE_CHECKING:  # scipy's rotations are imported where a pointing loop runs
    from scipy.spatial.transform import Rotation

_POS = Annotated[float, float_bounds(0.0, open_lo=True)]
_BOUND = Annotated[float, float_bounds(0.0, 1.0, open_lo=True)]


class PointingConfig(AttitudeEstimatorTables):
    """The ``[attitude]`` table of an intercept scenario: the loop holding the axis."""

    options_prefix: ClassVar[str] = "attitude.estimator_options"

    inertia_kgm2: Vector3[Inertia] = declared((40.0, 50.0, 60.0), "principal inertia, kg m^2")
    controller: Literal["pd", "lqr"] = declared("pd", "quaternion PD or LQR")
    estimator: str = declared("box", "attitude estimator (registered name)")
    control_period_s: Annotated[float, float_bounds(1e-3, 1.0)] = declared(
        0.05, "control period, s"
    )
    k_q: _POS = declared(0.5, "PD attitude gain, 1/s^2")
    k_w: _POS = declared(1.0, "PD rate gain, 1/s")
    lqr_q: Vector6[_POS] = declared((0.5, 0.5, 0.5, 0.25, 0.25, 0.25), "LQR state weights")
    lqr_r: Vector3[_POS] = declared((1.0, 1.0, 1.0), "LQR control weights")
    torque_max_Nm: _POS = declared(0.2, "wheel torque limit, N m")
    momentum_max_Nms: _POS = declared(5.0, "wheel momentum limit, N m s")
    meas_angle_bound_deg: _BOUND = declared(0.005, "star tracker error bound, deg")
    meas_rate_bound_degps: _BOUND = declared(0.0005, "gyro error bound, deg/s")
    disturbance_Nm: Annotated[float, float_bounds(0.0, 10.0)] = declared(
        1e-3, "disturbance torque bound per axis, N m"
    )
    disturbance: Literal["constant", "random", "game"] = declared("random", "disturbance kind")
    initial_error_deg: Vector3[Annotated[float, float_bounds(-30.0, 30.0)]] = declared(
        (0.5, -0.3, 0.2), "initial pointing error (rotation vector), deg"
    )
    initial_rate_degps: Vector3[Annotated[float, float_bounds(-10.0, 10.0)]] = declared(
        (0.0, 0.0, 0.0), "deg/s"
    )

    @model_validator(mode="after")
    def _buildable(self) -> PointingConfig:
        if self.estimator not in registry.names("attitude"):
            allowed = ", ".join(registry.names("attitude"))
            raise ValueError(
                f"field 'attitude.estimator' must be one of {allowed} (got {self.estimator!r})"
            )
        try:
            self.law(RigidBody.diagonal(self.inertia_kgm2))
        except ValueError as exc:
            raise ValueError(f"table 'attitude' must describe a valid controller: {exc}") from None
        return self

    def law(self, body: RigidBody) -> QuaternionPD | LQRController:
        if self.controller == "pd":
            return QuaternionPD(body, self.k_q, self.k_w)
        return LQRController(body.inertia_kgm2, self.lqr_q, self.lqr_r)


@dataclass
class PointingLoop:
    """A reaction-wheel attitude loop holding the guidance frame (mutable simulator state).

    Build it with :meth:`from_table`; all randomness comes from ``rng``.
    """

    body: RigidBody
    law: QuaternionPD | LQRController
    wheels: ReactionWheels
    loop: EstimatorLoop
    period_s: float
    disturbance: str
    rng: np.random.Generator
    x: np.ndarray  # (1, 10): q, w, h
    time_s: float = 0.0
    carry_s: float = 0.0
    belief: Any = None
    known: AttitudeControl | None = None
    d_const: np.ndarray = field(default_factory=lambda: np.zeros((1, 3)))
    energy_N2m2s: float = 0.0
    max_error_rad: float = 0.0
    max_bound_rad: float = 0.0
    truth_outside: int = 0
    steps: int = 0

    @classmethod
    def from_config(cls, t: PointingConfig, rng: np.random.Generator) -> PointingLoop:
        """The loop of a validated ``[attitude]`` table; all randomness from ``rng``."""
        body = RigidBody.diagonal(t.inertia_kgm2)
        law = t.law(body)
        d = t.disturbance_Nm
        model = AttitudeModel(
            body.inertia_kgm2,
            d,
            np.radians(t.meas_angle_bound_deg),
            np.radians(t.meas_rate_bound_degps),
        )
        from scipy.spatial.transform import Rotation  # here: intercepts without the loop skip it

        x = np.zeros((1, 10))
        x[0, 0:4] = Rotation.from_rotvec(np.radians(t.initial_error_deg)).as_quat()
        x[0, 4:7] = np.radians(t.initial_rate_degps)
        self = cls(
            body=body,
            law=law,
            wheels=ReactionWheels(t.torque_max_Nm, t.momentum_max_Nms),
            loop=EstimatorLoop(t.estimator, model, t.estimator_options),
            period_s=t.control_period_s,
            disturbance=t.disturbance,
            rng=rng,
            x=x,
            d_const=rng.uniform(-d, d, (1, 3)),
        )
        self.belief = self.loop.start(self._measure())
        self._record()
        return self

    def _measure(self) -> AttitudeMeasurement:
        return draw_measurement(self.x, self.loop.model, self.rng)

    def _record(self) -> None:
        self.truth_outside += int(np.sum(~self.loop.inside(self.belief, self.x)))
        self.max_error_rad = max(self.max_error_rad, self.true_error.magnitude())
        self.max_bound_rad = max(self.max_bound_rad, self.knowledge_bound_rad)

    def _one_period(self) -> None:
        T = self.period_s
        h = self.x[:, 7:10]
        x_est = np.concatenate([self.loop.centre(self.belief), h], axis=-1)
        u = self.wheels.limit(self.law.from_belief(PointBelief(x_est)), h, T)
        dmax = self.loop.model.disturbance_bound_Nm
        if self.disturbance == "game":
            d = -dmax * np.sign(u)
        elif self.disturbance == "random":
            d = self.rng.uniform(-1.0, 1.0, (1, 3)) * dmax
        else:
            d = self.d_const
        known = AttitudeControl.held(u, h, T)
        self.x, bad = advance_checked(rk4_step, self.body, self.x, (u, T, d), 1, T, slice(4, 7))
        if np.any(bad):  # the axis is lost: the run cannot go on (a failed run, said why)
            raise LoopDiverged.of(
                bad, self.x[:, 4:7], self.time_s + T, T, "the attitude loop holding the axis"
            )
        self.belief = self.loop.step(self.belief, known, T, self._measure())
        self.energy_N2m2s += float(np.sum(u * u)) * T
        self.time_s += T
        self.steps += 1
        self._record()

    def step(self, dt_s: float) -> None:
        """Advance by ``dt_s`` seconds in whole control periods (remainder carried)."""
        if not dt_s >= 0:
            raise ValueError(f"dt_s must be >= 0, got {dt_s}")
        self.carry_s += dt_s
        n = int(np.floor(self.carry_s / self.period_s + 1e-9))
        for _ in range(n):
            self._one_period()
        self.carry_s = max(self.carry_s - n * self.period_s, 0.0)

    @property
    def true_error(self) -> Rotation:
        """True rotation body -> guidance frame."""
        from scipy.spatial.transform import Rotation

        return Rotation.from_quat(self.x[0, 0:4])

    @property
    def estimated_error(self) -> Rotation:
        """The estimator's centre of :attr:`true_error`."""
        from scipy.spatial.transform import Rotation

        return Rotation.from_quat(self.loop.centre(self.belief)[0, 0:4])

    @property
    def knowledge_bound_rad(self) -> float:
        """Bound on the angle between :attr:`true_error` and :attr:`estimated_error`."""
        return float(self.belief.knowledge_bound_rad(self.loop.model)[0])

    def summary(self) -> dict[str, Any]:
        return {
            "estimator": self.loop.name,
            "time_s": self.time_s,
            "control_steps": self.steps,
            "max_pointing_error_deg": float(np.degrees(self.max_error_rad)),
            "final_pointing_error_deg": float(np.degrees(self.true_error.magnitude())),
            "final_knowledge_error_deg": float(
                np.degrees((self.estimated_error.inv() * self.true_error).magnitude())
            ),
            "max_knowledge_bound_deg": float(np.degrees(self.max_bound_rad)),
            "energy_N2m2s": self.energy_N2m2s,
            "truth_outside": self.truth_outside,
            "empty_steps": int(np.sum(self.loop.empty_steps(self.belief))),
            "unbounded_steps": int(np.sum(self.loop.unbounded_steps(self.belief))),
        }


AXIS = {"lateral": 1, "vertical": 2}


class PointingCoupling:
    """Per-run adapter between a pointing loop and the engagement loop."""

    def __init__(self, loop: Any):
        self.loop = loop
        self.kb_rad = float(loop.knowledge_bound_rad)
        self.max_residual_rad = 0.0
        self.max_bound_rad = self.kb_rad
        # the sets take the bound at the start for the whole run: count the steps where
        # the loop's bound grew past it (the premise no longer guaranteed) and where the
        # true residual did (the premise failed: a bearing or an impulse may lie outside
        # the bounds the sets took)
        self.bound_exceeded_steps = 0
        self.residual_over_bound_steps = 0

    def widen(
        self, model: ChannelModel, fuel_mps: float | None = None, approach_s: float = 0.0
    ) -> ChannelModel:
        """The intercept model with the bearing bound widened by the knowledge bound;
        with ``fuel_mps`` (the most the impulses may spend) its drifts widened too: a
        rotated impulse ``dv`` changes the closing speed by up to ``kb |dv|``, so all of
        them by ``kb fuel``, and the range by that times the approach ``approach_s``."""
        b = model.bearing_bound
        widened = BearingBound(b.start_rad + self.kb_rad, b.end_rad + self.kb_rad, b.ref_range_m)
        model = replace(model, bearing_bound=widened)
        if fuel_mps is None:
            return model
        dv = self.kb_rad * fuel_mps
        drift_m = model.range_drift_m + dv * approach_s
        if not drift_m < 0.5 * model.eps_m:
            raise ValueError(
                f"with model.along_sight_drift the impulses, rotated by up to the attitude "
                f"knowledge bound {np.degrees(self.kb_rad):.3g} deg over the fuel reserve "
                f"{fuel_mps:g} m/s, move the range up to {drift_m:.3g} m, not under half of "
                f"eps ({0.5 * model.eps_m:g} m): a finer attitude measurement, a smaller "
                "guidance.reserve_mps, or the option off"
            )
        return replace(model, closing_drift_mps=model.closing_drift_mps + dv, range_drift_m=drift_m)

    def bearing_errors(self, r_guidance: np.ndarray, channels: Sequence[str]) -> list[float]:
        """Bearing error (rad) per channel left after correcting the body-axis
        measurement with the estimated pointing error."""
        r_body = self.loop.true_error.inv().apply(r_guidance)
        r_corr = self.loop.estimated_error.apply(r_body)
        residual = float((self.loop.estimated_error * self.loop.true_error.inv()).magnitude())
        bound = float(self.loop.knowledge_bound_rad)
        self.max_residual_rad = max(self.max_residual_rad, residual)
        self.max_bound_rad = max(self.max_bound_rad, bound)
        self.bound_exceeded_steps += int(bound > self.kb_rad)
        self.residual_over_bound_steps += int(residual > self.kb_rad)
        return [
            float(
                np.arctan2(r_corr[AXIS[c]], r_corr[0])
                - np.arctan2(r_guidance[AXIS[c]], r_guidance[0])
            )
            for c in channels
        ]

    def impulse(self, dv_cmd_mps: np.ndarray, channels: Sequence[str]):
        """Actual impulse (guidance axes) for a commanded one, and the commands as
        :class:`Impulse` values with their uncertainty ``kb |dv|``."""
        rot = self.loop.true_error * self.loop.estimated_error.inv()
        actual = rot.apply(dv_cmd_mps)
        dk = self.kb_rad * float(np.linalg.norm(dv_cmd_mps))
        return actual, [Impulse(float(dv_cmd_mps[AXIS[c]]), dk) for c in channels]

    def step(self, dt_s: float) -> None:
        self.loop.step(dt_s)

    def summary(self) -> dict[str, float | int]:
        out: dict[str, float | int] = {
            f"attitude_{k}": float(v)
            for k, v in self.loop.summary().items()
            if isinstance(v, int | float | np.number)
        }
        out["pointing_residual_max_deg"] = float(np.degrees(self.max_residual_rad))
        out["pointing_knowledge_bound_deg"] = float(np.degrees(self.kb_rad))
        out["pointing_bound_max_deg"] = float(np.degrees(self.max_bound_rad))
        out["pointing_bound_exceeded_steps"] = self.bound_exceeded_steps
        out["pointing_residual_over_bound_steps"] = self.residual_over_bound_steps
        return out
