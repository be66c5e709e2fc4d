"""The kinematic term the auxiliary model neglects, as an interval with its sign.

With the bearing ``alpha``, its rate ``omega`` and the planar angular momentum
``h = rho^2 omega = e w / cos^2(alpha)`` (``w`` the nominal zero-effort miss), the
true motion is a motion of seed 003's auxiliary model with the disturbance
(:mod:`kalman_vs_infoset.estim.intercept.slabs.estimator`, module docstring)::

    v = cos(alpha) a_perp - 2 omega^2 x tan(alpha)
      = cos(alpha) a_perp - 2 h^2 cos^3(alpha) sin(alpha) / x^3 .

The first term is what ``nu`` stands for. The second has the sign of ``-alpha``:
a line of sight off the axis always turns further off it. Its magnitude is bounded
above by :func:`kalman_vs_infoset.estim.intercept.kinematic.kinematic_margin_mps2`; it is
bounded *below* when neither ``w`` nor ``alpha`` can be zero over the step:

* ``|h| >= e |w|_min - nu dt rho_max`` (``cos^2 <= 1``; ``dh/dt = rho a_perp``, the
  term itself never changes ``h``);
* ``alpha`` moves by at most ``|omega| dt <= h_max dt / x_min^2`` over the step;
* ``g(a) = cos^3(a) sin(a)`` is unimodal on ``(0, pi/2)``: its minimum over an
  interval is at one end;
* ``x <= x_max``.

So ``v_kin`` lies in ``[-U, -L]`` (``alpha > 0``) or ``[L, U]`` (``alpha < 0``) with
``L = 2 h_min^2 g_min / x_max^3``. A set that takes this interval instead of ``+-U``
moves with the term instead of spreading by it: far from the axis (an unguided
truth kilometres off at a few hundred km, where the term is a hundred times
``nu``) that is the difference between the exact set of the nonlinear motion and a
set several times wider.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.intercept import kinematic
from kalman_vs_infoset.estim.intercept.kinematic import MAX_BEARING_RAD
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def kinematic_interval_mps2(
    w_lo_m: ArrayLike,
    w_hi_m: ArrayLike,
    alpha_lo_rad: ArrayLike,
    alpha_hi_rad: ArrayLike,
    x_min_m: ArrayLike,
    x_max_m: ArrayLike,
    dt_s: float,
    e_mps: float,
    nu_mps2: float,
) -> tuple[FloatArray, FloatArray]:
    """Interval of the neglected kinematic term over one step (module docstring).

    Parameters
    ----------
    w_lo_m, w_hi_m, alpha_lo_rad, alpha_hi_rad : array
        Intervals of the nominal zero-effort miss (m) and of the bearing (rad) at
        the step's start, one per group of states.
    x_min_m, x_max_m : array
        Smallest range over the step and largest at its start (m, > 0).
    dt_s, e_mps, nu_mps2 : float
        Step, nominal closing speed, bound of the acceleration across the line of
        sight.

    Returns
    -------
    lo, hi : arrays
        ``lo <= -2 omega^2 x tan(alpha) <= hi`` for every state of the group over
        the step (m/s^2).
    """
    # compiled (one loop over the groups; called every step with a handful of them)
    args = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (w_lo_m, w_hi_m, alpha_lo_rad, alpha_hi_rad,
                                               x_min_m, x_max_m))
    )  # fmt: skip
    flat = (np.ascontiguousarray(np.ravel(v)) for v in args)
    lo, hi = kinematic.kinematic_interval(
        *flat, float(dt_s), float(e_mps), float(nu_mps2), MAX_BEARING_RAD
    )
    return lo.reshape(args[0].shape), hi.reshape(args[0].shape)
