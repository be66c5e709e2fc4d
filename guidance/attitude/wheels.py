"""Reaction-wheel actuator and a batched fixed-step rigid-body plant (docs/models.md §2, 2.2).

The plant is the common one of :mod:`kalman_vs_infoset.guidance.attitude.plant`::

    J dw/dt + w x (J w + h) = M_ext + M_u,   dh/dt = -M_u,   dq/dt = 1/2 q (x) (w, 0)

(seed 001 eqs. (1)-(3); ``h`` is the wheel momentum ``L`` of the seed). This module
adds what the controllers of docs/models.md §2.2/2.3 need for speed:

* :class:`ReactionWheels`: three wheels along the body axes with a per-axis torque
  limit ``|M_u,i| <= M_max`` and momentum limit ``|h_i| <= L_max``;
* :func:`rk4_step`: one step of the shared RK4 (:mod:`kalman_vs_infoset.numerics.integrate`) of the
plant
  for a whole batch of states ``(..., 10)`` with the torque held constant over the
  step (zero-order hold: the controller is sampled once per step);
* :func:`simulate_closed_loop`: a sampled-data loop (controller every
  ``control_period_s``, ``substeps`` RK4 steps in between).

With the torque held over a control period ``T`` the wheel momentum changes
linearly, ``h(t+T) = h - M_u T``, so the momentum limit is enforced exactly by
clipping the torque to ``(h - L_max)/T <= M_u <= (h + L_max)/T``.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np
from kalman_vs_infoset.guidance.attitude.plant import (
    LoopDiverged,
    RigidBody,
    advance_checked,
    positive_finite,
)
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics import integrate
from kalman_vs_infoset.numerics.integrate import renormalised
from kalman_vs_infoset.numerics.rotations import cross, quaternion_rate

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ReactionWheels:
    """Three reaction wheels along the body axes.

    Parameters
    ----------
    torque_max_Nm : float
        Per-axis torque limit ``M_max`` (N m); ``inf`` for none.
    momentum_max_Nms : float
        Per-axis momentum limit ``L_max`` (N m s); ``inf`` for none.
    """

    torque_max_Nm: float = np.inf
    momentum_max_Nms: float = np.inf

    def __post_init__(self) -> None:
        for name in ("torque_max_Nm", "momentum_max_Nms"):
            value = float(getattr(self, name))
            if not value > 0 or np.isnan(value):
                raise ValueError(f"{name} must be positive (inf for no limit), got {value}")
            object.__setattr__(self, name, value)

    def limit(self, torque_cmd_Nm: ArrayLike, h_Nms: ArrayLike, period_s: float) -> FloatArray:
        """Torque the wheels deliver for a command held over ``period_s``.

        ``|M_u,i| <= M_max`` and ``|h_i - M_u,i period_s| <= L_max`` (the momentum
        limit reached within the period stops the wheel at ``L_max``). Works on
        batches ``(..., 3)``.
        """
        m = np.asarray(torque_cmd_Nm, dtype=float)
        h = np.asarray(h_Nms, dtype=float)
        lo = np.full(np.broadcast_shapes(m.shape, h.shape), -self.torque_max_Nm)
        hi = -lo
        if np.isfinite(self.momentum_max_Nms):
            # keep |h| <= L_max at the end of the period; a wheel already beyond the
            # limit (a bad initial state) may only unload.
            lo = np.maximum(lo, np.minimum((h - self.momentum_max_Nms) / period_s, 0.0))
            hi = np.minimum(hi, np.maximum((h + self.momentum_max_Nms) / period_s, 0.0))
        return np.clip(m, lo, hi)


def plant_rhs_batch(
    x: FloatArray,
    body: RigidBody,
    torque_Nm: FloatArray,
    ext_torque_Nm: FloatArray | float = 0.0,
) -> FloatArray:
    """Right-hand side of the plant for a batch of states ``(..., 10) = (q, w, h)``."""
    q, w, h = x[..., 0:4], x[..., 4:7], x[..., 7:10]
    jw = w @ body.inertia_kgm2.T
    rhs = ext_torque_Nm + torque_Nm - cross(w, jw + h)
    dw = rhs @ body.inertia_inv.T
    return np.concatenate(
        [quaternion_rate(q, w), dw, -np.broadcast_to(torque_Nm, w.shape)], axis=-1
    )


def rk4_step(
    body: RigidBody,
    x: FloatArray,
    torque_Nm: FloatArray,
    dt_s: float,
    ext_torque_Nm: FloatArray | float = 0.0,
) -> FloatArray:
    """One step of the shared RK4 (:mod:`kalman_vs_infoset.numerics.integrate`) of the plant with
    the torques held constant; renormalises ``q``."""
    return renormalised(
        integrate.rk4_step(plant_rhs_batch, x, dt_s, body, torque_Nm, ext_torque_Nm)
    )


@dataclass(frozen=True)
class Trajectory:
    """Sampled closed-loop trajectory: ``x[k]`` at ``time_s[k]``, ``torque_Nm[k]`` held after it."""

    time_s: FloatArray
    x: FloatArray
    torque_Nm: FloatArray


def simulate_closed_loop(
    body: RigidBody,
    wheels: ReactionWheels,
    control: Callable[[float, FloatArray], FloatArray],
    x0: ArrayLike,
    duration_s: float,
    control_period_s: float,
    substeps: int = 1,
    ext_torque: Callable[[float, FloatArray, FloatArray], FloatArray] | None = None,
) -> Trajectory:
    """Sampled-data closed loop: ``control(t, x)`` every ``control_period_s``, torque held.

    Raises :class:`~kalman_vs_infoset.guidance.attitude.plant.LoopDiverged` when a state
    leaves what the integration resolves (``plant.unresolved``); its ``trajectory`` holds
    the instants before (the torque of the period that diverged last).

    ``x`` is the plant state ``(q[4], w[3], h[3])`` (one system or a batch); the
    commanded torque passes through :meth:`ReactionWheels.limit` and is held while
    ``substeps`` RK4 steps integrate the plant. ``ext_torque(t, x, torque)`` gives an
    external (disturbance) torque held over the same period.

    ``duration_s`` and ``control_period_s`` must be positive finite numbers and
    ``substeps`` an integer >= 1 (ValueError, or TypeError for a wrong type).
    """
    # an infinite duration has no step count, an infinite period no time axis
    duration_s = positive_finite(duration_s, "duration_s")
    control_period_s = positive_finite(control_period_s, "control_period_s")
    if isinstance(substeps, bool) or not isinstance(substeps, numbers.Integral):
        raise TypeError(f"substeps must be an integer >= 1, got {substeps!r}")
    if substeps < 1:
        raise ValueError(f"substeps must be an integer >= 1, got {substeps!r}")
    n = int(round(duration_s / control_period_s))
    x = np.array(x0, dtype=float)
    dt = control_period_s / substeps
    xs = np.empty((n + 1, *x.shape))
    us = np.empty((n + 1, *x.shape[:-1], 3))
    xs[0] = x
    for k in range(n):
        t = k * control_period_s
        u = wheels.limit(control(t, x), x[..., 7:10], control_period_s)
        m_ext = 0.0 if ext_torque is None else ext_torque(t, x, u)
        us[k] = u
        x, bad = advance_checked(rk4_step, body, x, (u, dt, m_ext), substeps, dt, slice(4, 7))
        if np.any(bad):
            exc = LoopDiverged.of(bad, x[..., 4:7], t + control_period_s, dt)
            exc.trajectory = Trajectory(  # the states resolved, at k + 1 instants
                cast(FloatArray, np.arange(k + 1) * control_period_s), xs[: k + 1], us[: k + 1]
            )
            raise exc
        xs[k + 1] = x
    us[n] = us[n - 1] if n else 0.0
    time_s = cast(FloatArray, np.arange(n + 1) * control_period_s)  # float64 (stubs: floating)
    return Trajectory(time_s, xs, us)
