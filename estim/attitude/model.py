"""What the attitude estimators know: the rigid-body model, its inputs and measurements.

Shared by :mod:`estim.attitude.box.estimator` (set-membership) and
:mod:`estim.attitude.ukf.estimator`. The model is the common plant of docs/models.md §2 written for
an estimator::

    J_b dw/dt = M_u + d - w x (J_g w + h),      dq/dt = 1/2 q (x) (w, 0)

``J_g`` is the inertia in the angular momentum, ``J_b`` the one that divides the
torque; both are ``J`` for reaction wheels and gyrodines (``h`` their momentum), and
for the three-rotor gyrostat of seed 004 eq. (1.1) ``J_g = diag(A)``, ``J_b =
diag(A - J)``, ``h = J phi'`` (relative rotor momentum), ``M_u = -u``: with
``J (phi'' + x') = u`` the seed's ``(A - J) x' = K x x - u + v`` is the line above.

Known inputs of one step (:class:`AttitudeControl`): the body torque ``M_u`` held
over the step and an interval ``[h_lo, h_hi]`` that contains the actuator momentum
over the whole step (the loops know it from their actuators: wheel speeds, gyrodine
angles, rotor tachometers). Unknown: the disturbance ``|d_i| <= D_i``.

Measurements (:class:`AttitudeMeasurement`): an attitude ``q_m = q exp(n)`` with a
body-frame error rotation ``|n_i| <= b_a`` per axis, and a rate ``w_m = w + m`` with
``|m_i| <= b_w``. Everything is batched over a leading axis of ``R`` runs.

Quaternions are scalar last (scipy's ``Rotation``); ``exp``/``log`` are
``Rotation.from_rotvec``/``as_rotvec`` (:mod:`kalman_vs_infoset.numerics.rotations`).
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.estim.base import Belief
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.integrate import renormalised, rk4_step
from kalman_vs_infoset.numerics.rotations import cross, qexp, qmul, quaternion_rate

FloatArray = NDArray[np.float64]


def _vec3(value: ArrayLike, name: str, positive: bool = False) -> FloatArray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(arr)) or np.any(arr < 0) or (positive and np.any(arr == 0)):
        raise ValueError(f"{name} must be finite and >= 0 per axis, got {arr}")
    arr.setflags(write=False)
    return arr


def _inertia(value: ArrayLike, name: str) -> FloatArray:
    arr = np.array(value, dtype=float)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3) or not np.allclose(arr, arr.T):
        raise ValueError(f"{name} must be a symmetric 3x3 matrix (or its diagonal)")
    if np.any(np.linalg.eigvalsh(arr) <= 0):
        raise ValueError(f"{name} must be positive definite")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class AttitudeModel:
    """Estimator model: inertias, disturbance bound, measurement bounds.

    Parameters
    ----------
    inertia_kgm2 : (3, 3) or (3,)
        ``J_g`` (momentum ``J_g w + h``).
    disturbance_bound_Nm : float or (3,)
        ``D``: ``|d_i| <= D_i``.
    meas_angle_bound_rad, meas_rate_bound_radps : float or (3,)
        ``b_a``, ``b_w``: per-axis bounds of the attitude and rate errors.
    effective_inertia_kgm2 : (3, 3) or (3,), optional
        ``J_b`` (divides the torque); ``J_g`` when omitted.
    """

    # typed as what __post_init__ stores (read-only float arrays); at run time lists,
    # floats and arrays are accepted and converted
    inertia_kgm2: FloatArray
    disturbance_bound_Nm: FloatArray | float
    meas_angle_bound_rad: FloatArray | float
    meas_rate_bound_radps: FloatArray | float
    effective_inertia_kgm2: FloatArray | None = None
    j_b_inv: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        j_g = _inertia(self.inertia_kgm2, "inertia_kgm2")
        j_b = j_g if self.effective_inertia_kgm2 is None else _inertia(
            self.effective_inertia_kgm2, "effective_inertia_kgm2"
        )  # fmt: skip
        object.__setattr__(self, "inertia_kgm2", j_g)
        object.__setattr__(self, "effective_inertia_kgm2", j_b)
        inv = np.linalg.inv(j_b)
        inv.setflags(write=False)
        object.__setattr__(self, "j_b_inv", inv)
        object.__setattr__(
            self, "disturbance_bound_Nm", _vec3(self.disturbance_bound_Nm, "disturbance_bound_Nm")
        )
        object.__setattr__(
            self,
            "meas_angle_bound_rad",
            _vec3(self.meas_angle_bound_rad, "meas_angle_bound_rad", positive=True),
        )
        object.__setattr__(
            self,
            "meas_rate_bound_radps",
            _vec3(self.meas_rate_bound_radps, "meas_rate_bound_radps", positive=True),
        )


@dataclass(frozen=True)
class AttitudeControl:
    """Known inputs over one step: body torque ``M_u`` and an enclosure of ``h`` (batched)."""

    torque_Nm: FloatArray
    h_lo_Nms: FloatArray
    h_hi_Nms: FloatArray

    def __post_init__(self) -> None:
        for name in ("torque_Nm", "h_lo_Nms", "h_hi_Nms"):
            arr = np.array(np.atleast_2d(getattr(self, name)), dtype=float)
            if not np.isfinite(arr).all():  # a NaN torque gave a NaN belief with status ok
                raise ValueError(f"{name} must be finite")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        shapes = {a.shape for a in (self.torque_Nm, self.h_lo_Nms, self.h_hi_Nms)}
        if len(shapes) != 1 or self.torque_Nm.ndim != 2 or self.torque_Nm.shape[1] != 3:
            raise ValueError(f"torque_Nm, h_lo_Nms and h_hi_Nms must be (R, 3) each; got {shapes}")
        if np.any(self.h_lo_Nms > self.h_hi_Nms):
            raise ValueError("h_lo_Nms must not exceed h_hi_Nms")

    @property
    def runs(self) -> int:
        """Number of runs (rows)."""
        return int(self.torque_Nm.shape[0])

    @classmethod
    def held(cls, torque_Nm: ArrayLike, h0_Nms: ArrayLike, dt_s: float, h_err_Nms: float = 0.0):
        """Momentum ``h(s) = h0 - M_u s`` (``dh/dt = -M_u``) over ``[0, dt_s]``, +- ``h_err``."""
        m = np.atleast_2d(np.asarray(torque_Nm, dtype=float))
        h0 = np.atleast_2d(np.asarray(h0_Nms, dtype=float))
        h1 = h0 - m * dt_s
        return cls(m, np.minimum(h0, h1) - h_err_Nms, np.maximum(h0, h1) + h_err_Nms)

    @classmethod
    def zero(cls, runs: int) -> AttitudeControl:
        z = np.zeros((runs, 3))
        return cls(z, z, z)


@dataclass(frozen=True)
class AttitudeMeasurement:
    """Measured attitude quaternions ``(R, 4)`` and rates ``(R, 3)``."""

    quat: FloatArray
    rate_radps: FloatArray

    def __post_init__(self) -> None:
        q = np.array(np.atleast_2d(self.quat), dtype=float)
        w = np.array(np.atleast_2d(self.rate_radps), dtype=float)
        # (R, 4) and (R, 3) of one R: a (2, 3) "quaternion" was taken, and failed later
        # as a numpy broadcast error deep in an estimator
        if q.ndim != 2 or q.shape[1] != 4 or w.ndim != 2 or w.shape[1] != 3:
            raise ValueError(
                f"quat must be (R, 4) and rate_radps (R, 3) (or one row each); got "
                f"{np.shape(self.quat)} and {np.shape(self.rate_radps)}"
            )
        if q.shape[0] != w.shape[0]:
            raise ValueError(f"quat has {q.shape[0]} runs and rate_radps {w.shape[0]}")
        norm = np.linalg.norm(q, axis=-1, keepdims=True)
        if not (np.isfinite(q).all() and np.all(norm > 0.0)):
            raise ValueError("quat must be finite and non-zero")
        q /= norm
        if not np.isfinite(w).all():
            raise ValueError("rate_radps must be finite")
        for arr in (q, w):
            arr.setflags(write=False)
        object.__setattr__(self, "quat", q)
        object.__setattr__(self, "rate_radps", w)

    @property
    def runs(self) -> int:
        """Number of runs (rows)."""
        return int(self.quat.shape[0])


def run_states(state: ArrayLike, runs: int) -> FloatArray:
    """The true states ``(q, w, ...)`` of a belief's runs as an ``(R, 7+)`` array (one
    state alone for a single run); one line for another shape: a state of one run was
    broadcast over a belief of several (the box answered for all), or failed as a numpy
    error."""
    s = np.atleast_2d(np.asarray(state, dtype=float))
    if s.ndim != 2 or s.shape[0] != runs or s.shape[1] < 7:
        raise ValueError(
            f"a state (q, w, ...) per run: ({runs}, 7) or wider, got {np.shape(state)}"
        )
    return s


def check_runs(belief_runs: int, given: int, what: str) -> None:
    """A measurement or control has one row per run of the belief: a single row was
    broadcast over every run, silently, and other counts failed as numpy broadcast
    errors."""
    if given != belief_runs:
        raise ValueError(
            f"the belief holds {belief_runs} runs and the {what} {given}: one row a run"
        )


@dataclass(frozen=True)
class AttitudePrior:
    """What an attitude estimator knows before its first update (the prior of
    :meth:`estim.base.Estimator.initial` for attitude): the first measurement, whose
    errors are within the model's bounds."""

    measurement: AttitudeMeasurement


@dataclass(frozen=True)
class RateComponent:
    """The body rate about one axis, ``w[axis]`` (rad/s), of states ``(..., 7)``
    (``q`` then ``w``): the function whose :meth:`AttitudeBelief.extremes` every
    attitude belief gives. It is linear in the rate coordinates, so a box's vertices
    hold its extremes; the quaternion's components are not monotone in the attitude
    error, and a belief refuses them (``TypeError``) rather than return inner values."""

    axis: int

    def __post_init__(self) -> None:
        if self.axis not in (0, 1, 2):
            raise ValueError(f"axis must be 0, 1 or 2, got {self.axis!r}")

    def __call__(self, states: ArrayLike) -> FloatArray:
        return np.asarray(states, dtype=float)[..., 4 + self.axis]


def rate_component(fn: object, belief: str) -> RateComponent:
    """``fn`` if it is a :class:`RateComponent`, else ``TypeError``: a set of attitudes
    bounds no other function by its vertices (their values are not extremes)."""
    if not isinstance(fn, RateComponent):
        raise TypeError(
            f"{belief} bounds RateComponent only (a function's values at its vertices are "
            f"not its extremes in general); got {type(fn).__name__}"
        )
    return fn


class AttitudeBelief(Belief):
    """Beliefs about ``(q, w)`` of a batch of ``R`` runs (one estimator, paired runs):
    what an attitude loop asks besides the :class:`~estim.base.Belief` questions."""

    @property
    @abstractmethod
    def runs(self) -> int:
        """Number of runs in the batch."""

    @abstractmethod
    def inside(self, state: ArrayLike) -> NDArray[np.bool_]:
        """Per run: whether the true state ``(q, w, ...)`` lies in the belief."""

    @abstractmethod
    def attitude_bound_rad(self) -> FloatArray:
        """Per run: bound of the angle between the true and the centre attitude."""

    def knowledge_bound_rad(self, model: AttitudeModel) -> FloatArray:
        """Per run: a bound of the angle between the true and the centre attitude that
        a consumer may rely on (an axis held by this belief widens its bearing bounds
        by it): the belief's own bound (a point belief says the measurement's)."""
        return self.attitude_bound_rad()

    @property
    @abstractmethod
    def empty_counts(self) -> NDArray[np.int_]:
        """Per run: updates so far whose data contradicted the model."""

    @property
    def unbounded_counts(self) -> NDArray[np.int_]:
        """Per run: predictions so far whose set was the whole space (a set estimator
        whose enclosure could not be closed); none for the other beliefs."""
        return np.zeros(self.runs, dtype=int)


class NeverEmptyBelief(AttitudeBelief):
    """An attitude belief that no data can contradict (a point, a Kalman filter's
    moments): never empty, no contradicted update in any run."""

    @property
    def is_empty(self) -> bool:
        return False

    @property
    def empty_counts(self) -> NDArray[np.int_]:
        return np.zeros(self.runs, dtype=int)


def check_step(dt_s: float) -> None:
    """A prediction's step: a finite number of seconds > 0."""
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise ValueError(f"dt_s must be a finite number > 0, got {dt_s}")


def draw_measurement(
    state: ArrayLike, model: AttitudeModel, rng_or_rngs, bound_scale: float = 1.0
) -> AttitudeMeasurement:
    """A measurement of ``state = (q, w, ...)`` (R, >=7) with errors uniform in the bounds.

    ``rng_or_rngs``: one Generator, or one per run (paired realisations).
    """
    x = np.atleast_2d(np.asarray(state, dtype=float))
    runs = x.shape[0]
    rngs = rng_or_rngs if isinstance(rng_or_rngs, list | tuple) else [rng_or_rngs] * runs
    u = np.stack([g.uniform(-1.0, 1.0, 6) for g in rngs]) * bound_scale
    n = u[:, 0:3] * model.meas_angle_bound_rad
    m = u[:, 3:6] * model.meas_rate_bound_radps
    return AttitudeMeasurement(qmul(x[:, 0:4], qexp(n)), x[:, 4:7] + m)


def rate_rhs(
    model: AttitudeModel, w: FloatArray, torque_Nm: FloatArray, h_Nms: FloatArray
) -> FloatArray:
    """``dw/dt = J_b^-1 (M_u - w x (J_g w + h))`` (nominal: no disturbance), batched."""
    jw = w @ model.inertia_kgm2.T
    return (torque_Nm - cross(w, jw + h_Nms)) @ model.j_b_inv.T


def rk4_attitude(
    model: AttitudeModel,
    q: FloatArray,
    w: FloatArray,
    torque_Nm: FloatArray,
    h_Nms: FloatArray,
    dt_s: float,
    substeps: int = 1,
) -> tuple[FloatArray, FloatArray]:
    """Nominal model (``d = 0``, ``h`` held) by the shared RK4
    (:mod:`kalman_vs_infoset.numerics.integrate`); ``q`` renormalised after every substep."""

    def rhs(x: FloatArray) -> FloatArray:
        w_ = x[..., 4:7]
        return np.concatenate(
            [quaternion_rate(x[..., 0:4], w_), rate_rhs(model, w_, torque_Nm, h_Nms)], axis=-1
        )

    x = np.concatenate([q, w], axis=-1)
    for _ in range(substeps):
        x = renormalised(rk4_step(rhs, x, dt_s / substeps))
    return x[..., 0:4], x[..., 4:7]
