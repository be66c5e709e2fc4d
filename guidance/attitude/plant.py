"""Common attitude plant: a rigid body carrying an angular-momentum actuator.

Equations (docs/models.md §2)::

    J dw/dt + w x (J w + h) = M_ext + M_u        (body rates w, rad/s)
    dh/dt = -M_u                                  (actuator momentum h, N m s)
    dq/dt = 1/2 q (x) (w, 0)                      (unit quaternion, scalar last)

``M_u`` is the control torque acting on the body (the reaction of the wheels or
gyrodines), so the total angular momentum ``J w + h`` changes only through
``M_ext``. Quaternions follow scipy's ``Rotation`` convention (scalar last,
body-to-inertial); conversions go through ``Rotation``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly
from kalman_vs_infoset.numerics.rotations import cross, quaternion_rate

# scipy is imported where it is used, so that importing the attitude models stays light
# (``kvi pd-gains`` reads the gain study's settings to declare its options)
if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation


def _checked(a: ArrayLike, shape: tuple[int, ...], name: str) -> NDArray[np.float64]:
    arr = np.array(a, dtype=float)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return readonly(arr)


def positive_finite(value: object, name: str) -> float:
    """``value`` as a float, refused unless it is a positive finite real number.

    Parameters
    ----------
    value : object
        The number to check (a Python or numpy real scalar, or a 0-d array).
    name : str
        The argument's name, as the messages say it.

    Returns
    -------
    float

    Raises
    ------
    TypeError
        ``value`` is not a real number (a string, None, a bool, an array).
    ValueError
        ``value`` is zero, negative, infinite or NaN.
    """
    arr = np.asarray(value)
    # "1" or True would pass float() and compare as numbers: a wrong type, said as one
    if arr.ndim != 0 or arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a positive finite number, got {value!r}")
    number = float(arr)
    if not (number > 0 and np.isfinite(number)):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return number


@dataclass(frozen=True)
class RigidBody:
    """Rigid-body inertia (kg m^2 = N m s^2), symmetric positive definite."""

    inertia_kgm2: NDArray[np.float64]
    inertia_inv: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        inertia = _checked(self.inertia_kgm2, (3, 3), "inertia_kgm2")
        if not np.allclose(inertia, inertia.T):
            raise ValueError("inertia_kgm2 must be symmetric")
        if np.any(np.linalg.eigvalsh(inertia) <= 0):
            raise ValueError("inertia_kgm2 must be positive definite")
        object.__setattr__(self, "inertia_kgm2", inertia)
        inv = np.linalg.inv(inertia)
        inv.setflags(write=False)
        object.__setattr__(self, "inertia_inv", inv)

    @classmethod
    def diagonal(cls, j_kgm2: ArrayLike) -> RigidBody:
        return cls(np.diag(np.asarray(j_kgm2, dtype=float)))


@dataclass(frozen=True)
class AttitudeState:
    """Attitude ``q`` (scalar last), body rate ``w_radps``, actuator momentum ``h_Nms``."""

    q: NDArray[np.float64]
    w_radps: NDArray[np.float64]
    h_Nms: NDArray[np.float64]

    def __post_init__(self) -> None:
        q = np.array(self.q, dtype=float)
        norm = np.linalg.norm(q)
        if q.shape != (4,) or not np.isfinite(norm) or norm == 0:
            raise ValueError("q must be a non-zero 4-vector (scalar last)")
        q = q / norm
        q.setflags(write=False)
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "w_radps", _checked(self.w_radps, (3,), "w_radps"))
        object.__setattr__(self, "h_Nms", _checked(self.h_Nms, (3,), "h_Nms"))

    @property
    def rotation(self) -> Rotation:
        from scipy.spatial.transform import Rotation

        return Rotation.from_quat(self.q)

    def as_vector(self) -> NDArray[np.float64]:
        """State as one vector ``(q[4], w[3], h[3])``."""
        return np.concatenate([self.q, self.w_radps, self.h_Nms])

    @classmethod
    def from_vector(cls, x: ArrayLike) -> AttitudeState:
        x = np.asarray(x, dtype=float)
        return cls(x[0:4], x[4:7], x[7:10])


def attitude_rhs(
    x: NDArray[np.float64],
    body: RigidBody,
    torque_Nm: NDArray[np.float64],
    ext_torque_Nm: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Right-hand side of the plant for the state vector ``(q, w, h)``."""
    q, w, h = x[0:4], x[4:7], x[7:10]
    jw = body.inertia_kgm2 @ w
    dw = body.inertia_inv @ (ext_torque_Nm + torque_Nm - cross(w, jw + h))
    return np.concatenate([quaternion_rate(q, w), dw, -torque_Nm])


def propagate(
    body: RigidBody,
    state: AttitudeState,
    torque_Nm: ArrayLike,
    dt_s: float,
    ext_torque_Nm: ArrayLike = (0.0, 0.0, 0.0),
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> AttitudeState:
    """Hold ``torque_Nm`` (and ``ext_torque_Nm``) constant over ``dt_s``; return the new state.

    Integrates with ``solve_ivp`` (DOP853); the quaternion is renormalised at the end.
    ``dt_s`` must be a positive finite number (ValueError otherwise).
    """
    from scipy.integrate import solve_ivp

    # an infinite step never ends: solve_ivp keeps stepping towards t = inf
    dt_s = positive_finite(dt_s, "dt_s")
    m_u = np.asarray(torque_Nm, dtype=float)
    m_ext = np.asarray(ext_torque_Nm, dtype=float)
    if not (np.isfinite(m_u).all() and np.isfinite(m_ext).all()):
        # solve_ivp's step control never ends on a NaN derivative
        raise ValueError(f"torques must be finite, got {m_u.tolist()} and {m_ext.tolist()}")
    sol = solve_ivp(
        lambda _t, x: attitude_rhs(x, body, m_u, m_ext),
        (0.0, dt_s),
        state.as_vector(),
        method="DOP853",
        rtol=rtol,
        atol=atol,
    )
    if not sol.success:  # pragma: no cover - DOP853 on a smooth field does not fail
        raise RuntimeError(f"attitude propagation failed: {sol.message}")
    return AttitudeState.from_vector(sol.y[:, -1])


#: most one fixed integration step of a closed loop may turn the body, rad. The loops'
#: RK4 turns the quaternion by ``|w| dt`` a step with an error of about
#: ``2 (|w| dt / 2)^5 / 5!`` (5e-4 rad at 1 rad a step, 1e-2 at 2 rad): the loops' own
#: rates stay orders below it, and an unstable loop's grow past it within a few steps of
#: overflowing. A state past it (or not finite) no longer simulates the plant: the loop
#: has diverged (:class:`LoopDiverged`).
MAX_TURN_PER_STEP_RAD = 1.0


def unresolved(w_radps: ArrayLike, x: ArrayLike, dt_s: float) -> NDArray[np.bool_]:
    """Per state of a batch: whether the closed loop has left what its integration
    resolves, ``not all(isfinite(x))`` or ``|w| dt_s > MAX_TURN_PER_STEP_RAD``.

    Parameters
    ----------
    w_radps : array_like (..., 3)
        Body rates.
    x : array_like (..., n)
        The whole states (every component must be finite).
    dt_s : float
        The integration step.

    Returns
    -------
    ndarray of bool (...,)
        True where the state has left what the integration resolves.
    """
    finite = np.all(np.isfinite(x), axis=-1)
    with np.errstate(over="ignore", invalid="ignore"):  # an overflowed rate is unresolved
        fast = np.linalg.norm(w_radps, axis=-1) * dt_s > MAX_TURN_PER_STEP_RAD
    return ~finite | fast


def advance_checked(
    step: Callable[..., NDArray[np.float64]],
    model: object,
    x: NDArray[np.float64],
    inputs: tuple,
    substeps: int,
    dt_s: float,
    rates: slice,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """``substeps`` integration steps ``x <- step(model, x, *inputs)`` and
    :func:`unresolved` of the result (its rates at ``x[..., rates]``): what every closed
    loop does between two samples. numpy's overflow warnings are silenced inside, since
    a state that overflows is what the check reports."""
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(substeps):
            x = step(model, x, *inputs)
    return x, unresolved(x[..., rates], x, dt_s)


class LoopDiverged(ArithmeticError):
    """A closed attitude loop left what its fixed-step integration resolves
    (:func:`unresolved`): the sampled-data loop is unstable for its scenario (or its
    step too coarse for the rates it reached). The loops report such a run as
    ``diverged`` (a counted outcome, docs/models.md §3.1); a batch of runs raises this
    so that each run can be simulated alone.

    Parameters
    ----------
    runs : sequence of int
        The diverged runs' indices in the batch.
    time_s : float
        The first instant the loop checked at which a state was unresolved (the loops
        check where the controller samples).
    rate_radps : float
        The largest body rate there (inf or NaN for a state that overflowed).
    dt_s : float
        The integration step.
    batch : int, default 1
        The runs the loop simulated together (the message names the diverged ones when
        there are several).
    loop : str, default "the closed loop"
        What diverged, as the message names it.
    """

    #: what the loop resolved before it diverged, if the loop keeps it (its own type)
    trajectory: object = None

    def __init__(
        self,
        runs,
        time_s: float,
        rate_radps: float,
        dt_s: float,
        batch: int = 1,
        loop: str = "the closed loop",
    ) -> None:
        self.runs = tuple(int(r) for r in runs)
        self.time_s, self.rate_radps, self.dt_s = float(time_s), float(rate_radps), float(dt_s)
        what = (
            f"body rate {np.degrees(self.rate_radps):.3g} deg/s, more than "
            f"{MAX_TURN_PER_STEP_RAD:g} rad in an integration step of {self.dt_s:.3g} s"
            if np.isfinite(self.rate_radps) and self.rate_radps * self.dt_s > MAX_TURN_PER_STEP_RAD
            else "the state became non-finite"
        )
        which = f"; runs {list(self.runs)} of a batch of {batch}" if batch > 1 else ""
        super().__init__(f"{loop} diverged at t = {self.time_s:.6g} s ({what}{which})")

    @classmethod
    def of(
        cls, bad, w_radps, time_s: float, dt_s: float, loop: str = "the closed loop"
    ) -> LoopDiverged:
        """The error of the runs ``bad`` (a mask over the batch) at ``time_s``."""
        bad = np.atleast_1d(bad)
        w = np.atleast_2d(np.asarray(w_radps, dtype=float))[bad]
        with np.errstate(over="ignore", invalid="ignore"):
            rates = np.linalg.norm(w, axis=-1)
        rate = float(np.max(rates)) if rates.size else np.nan
        return cls(np.flatnonzero(bad), time_s, rate, dt_s, bad.size, loop)


def total_momentum_Nms(body: RigidBody, state: AttitudeState) -> NDArray[np.float64]:
    """Total angular momentum ``J w + h`` in body axes (conserved when M_ext = 0)."""
    return body.inertia_kgm2 @ state.w_radps + state.h_Nms


def attitude_error(q: ArrayLike, q_target: ArrayLike) -> Rotation:
    """Error rotation ``q_target^-1 * q`` (body attitude relative to the target)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat(q_target).inv() * Rotation.from_quat(q)
