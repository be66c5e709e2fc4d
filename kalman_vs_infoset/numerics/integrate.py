"""The fixed-step integrator every plant and every model propagation uses.

One classical Runge-Kutta step with the inputs held over it (zero-order hold: the
controllers are sampled once per step). Plants that carry a quaternion renormalise it
after the step themselves (:func:`renormalised`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def rk4_step(
    rhs: Callable[..., FloatArray], x: FloatArray, dt_s: float, *inputs: Any
) -> FloatArray:
    """``x(t + dt)`` of ``dx/dt = rhs(x, *inputs)`` by one classical RK4 step (a new array).

    ``x`` may be one state or a batch over leading axes; ``inputs`` are held constant.
    """
    k1 = rhs(x, *inputs)
    k2 = rhs(x + 0.5 * dt_s * k1, *inputs)
    k3 = rhs(x + 0.5 * dt_s * k2, *inputs)
    k4 = rhs(x + dt_s * k3, *inputs)
    return x + dt_s / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def renormalised(x: FloatArray, quaternion: slice = slice(0, 4)) -> FloatArray:
    """``x`` with its quaternion block scaled to unit norm (in place; returned)."""
    x[..., quaternion] /= np.linalg.norm(x[..., quaternion], axis=-1, keepdims=True)
    return x
