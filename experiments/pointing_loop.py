"""Attitude loop holding the longitudinal axis of the interceptor (SPEC 2.5, end-to-end).

It lives in ``experiments`` because it composes a whole simulated loop (plant,
noise, estimator, controller), as the other experiment runners do; ``guidance``
keeps the controllers themselves.

The spacecraft of Problem A carries reaction wheels; its attitude loop holds the body
axes on the guidance frame (target attitude = identity). The controller (quaternion
PD, SPEC 2.2, or LQR, SPEC 2.3) reads ``(q, w)`` from an estimator (``box``, ``ukf`` or
``perfect``, :mod:`experiments.attitude_est`) fed by bounded attitude and rate
measurements; the wheel momentum is known on board. Disturbance torques within
``|d_i| <= D``: ``constant`` (drawn once), ``random`` (redrawn every control period)
or ``game`` (``-D sign(M_u)``, opposing the control).

Contract used by the engagement (the lead's integration)::

    loop = PointingLoop.from_table(source, table, rng)
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

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from estim.attitude_model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from estim.attitude_perfect import PerfectAttitudeEstimator
from estim.base import PointBelief
from experiments.attitude_est import EstimatorLoop
from experiments.errors import InputError
from experiments.schema import Choice, Num, Vec, validate_table
from guidance.attitude.lqr import LQRController
from guidance.attitude.pd import QuaternionPD
from guidance.attitude.plant import RigidBody
from guidance.attitude.wheels import ReactionWheels, rk4_step

POS = Num(0.0, open_lo=True)
RULES = {
    "inertia_kgm2": Vec(POS, 3),
    "controller": Choice(("pd", "lqr")),
    "estimator": Choice(("box", "ukf", "perfect")),
    "control_period_s": Num(1e-3, 1.0),
    "k_q": POS,
    "k_w": POS,
    "lqr_q": Vec(POS, 6),
    "lqr_r": Vec(POS, 3),
    "torque_max_Nm": POS,
    "momentum_max_Nms": POS,
    "meas_angle_bound_deg": Num(0.0, 1.0, open_lo=True),
    "meas_rate_bound_degps": Num(0.0, 1.0, open_lo=True),
    "disturbance_Nm": Num(0.0, 10.0),
    "disturbance": Choice(("constant", "random", "game")),
    "initial_error_deg": Vec(Num(-30.0, 30.0), 3),
    "initial_rate_degps": Vec(Num(-10.0, 10.0), 3),
}
DEFAULTS = {
    "inertia_kgm2": (40.0, 50.0, 60.0),
    "controller": "pd",
    "estimator": "box",
    "control_period_s": 0.05,
    "k_q": 0.5,
    "k_w": 1.0,
    "lqr_q": (0.5, 0.5, 0.5, 0.25, 0.25, 0.25),
    "lqr_r": (1.0, 1.0, 1.0),
    "torque_max_Nm": 0.2,
    "momentum_max_Nms": 5.0,
    "meas_angle_bound_deg": 0.005,
    "meas_rate_bound_degps": 0.0005,
    "disturbance_Nm": 1e-3,
    "disturbance": "random",
    "initial_error_deg": (0.5, -0.3, 0.2),
    "initial_rate_degps": (0.0, 0.0, 0.0),
}


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
    def from_table(
        cls, source: str, table: Mapping[str, Any], rng: np.random.Generator
    ) -> PointingLoop:
        """Validate the ``[attitude]`` table (unknown keys and bad values: InputError)."""
        t = validate_table(source, dict(table), RULES, DEFAULTS, prefix="attitude.")
        body = RigidBody.diagonal(t["inertia_kgm2"])
        try:
            if t["controller"] == "pd":
                law: QuaternionPD | LQRController = QuaternionPD(body, t["k_q"], t["k_w"])
            else:
                law = LQRController(body.inertia_kgm2, t["lqr_q"], t["lqr_r"])
        except ValueError as exc:
            raise InputError(f"{source}: table 'attitude': {exc}") from None
        d = t["disturbance_Nm"]
        model = AttitudeModel(
            body.inertia_kgm2,
            d,
            np.radians(t["meas_angle_bound_deg"]),
            np.radians(t["meas_rate_bound_degps"]),
        )
        x = np.zeros((1, 10))
        x[0, 0:4] = Rotation.from_rotvec(np.radians(t["initial_error_deg"])).as_quat()
        x[0, 4:7] = np.radians(t["initial_rate_degps"])
        self = cls(
            body=body,
            law=law,
            wheels=ReactionWheels(t["torque_max_Nm"], t["momentum_max_Nms"]),
            loop=EstimatorLoop(t["estimator"], model),
            period_s=t["control_period_s"],
            disturbance=t["disturbance"],
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
        self.x = rk4_step(self.body, self.x, u, T, d)
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
        return Rotation.from_quat(self.x[0, 0:4])

    @property
    def estimated_error(self) -> Rotation:
        """The estimator's centre of :attr:`true_error`."""
        return Rotation.from_quat(self.loop.centre(self.belief)[0, 0:4])

    @property
    def knowledge_bound_rad(self) -> float:
        """Bound on the angle between :attr:`true_error` and :attr:`estimated_error`."""
        if isinstance(self.loop.estimator, PerfectAttitudeEstimator):
            return float(np.linalg.norm(self.loop.model.meas_angle_bound_rad))
        return float(self.loop.attitude_bound_rad(self.belief)[0])

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
        }
