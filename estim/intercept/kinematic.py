"""The kinematic term the auxiliary model neglects, bounded (docs/models.md §1.4).

For the truth, ``d(omega x^2)/dt = x cos(alpha) a_perp - 2 omega^2 x^2 tan(alpha)``: the
auxiliary model's ``d(omega x^2)/dt = v x`` leaves out the second term, which near the
target exceeds ``nu`` by orders of magnitude. The set estimators add a bound of it to
``nu`` (:func:`kinematic_margin_mps2`, the slab set per section) or bound it by a signed
interval per closing-speed piece (:func:`piece_kinematic`, the node set). The constants
below are the set estimators' shared numerics.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.intercept.model import ChannelModel, Range
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset._jit import njit
from kalman_vs_infoset.numerics.arrays import readonly

FloatArray = NDArray[np.float64]

#: relative outward margin of bearing strips (outward rounding, ~1e-13 rad)
STRIP_MARGIN = 1.0e-9
#: bearing (rad) up to which the slab set's kinematic margin is a bound (~86 deg)
MAX_BEARING_RAD = 1.5
#: |w| / x above which a slab set is reported ``"diverged"`` (emptied, not propagated)
DIVERGED_W_PER_X = 1.0e3


def range_x_interval(model: ChannelModel, measurement: Range) -> tuple[float, float]:
    """The axis ranges ``x`` a range measurement ``d`` admits, as the set estimators
    take them: ``d / (1 + b) cos(phi) <= x <= d / (1 - b)`` (``b`` the relative bound; the
    sets are in ``x = d cos(phi)``, ``phi`` the off-axis angle, the measurement's or else
    the model's largest), rounded outward by :data:`STRIP_MARGIN` and widened by the
    model's ``range_drift_m`` (a truth off its constant-speed line)."""
    b, d = model.range_rel_bound, measurement.range_m
    phi = measurement.off_axis_rad
    phi = model.max_off_axis_rad if phi is None else phi
    lo = d / (1.0 + b) * np.cos(phi) * (1.0 - STRIP_MARGIN) - model.range_drift_m
    hi = d / (1.0 - b) * (1.0 + STRIP_MARGIN) + model.range_drift_m
    return lo, hi


def kinematic_margin_mps2(
    w_abs_m: ArrayLike,
    alpha_abs_rad: ArrayLike,
    x_min_m: ArrayLike,
    x_max_m: ArrayLike,
    dt_s: float,
    e_mps: float,
    nu_mps2: float,
) -> FloatArray:
    """Bound of the kinematic term the auxiliary model neglects, over one step.

    With the planar angular momentum ``h = rho^2 omega = e w / cos^2(alpha)`` the term
    (module docstring) is ``2 omega^2 x tan(alpha) = 2 h^2 cos^3(alpha) sin(alpha) / x^3``.
    Over the step ``dh/dt = rho a_perp``, so ``|h| <= e |w_0| / cos^2(alpha_0) +
    nu dt rho_max``: unlike ``w``, ``h`` cannot grow through the term itself (the
    bound needs no fixed point; one built on ``w`` has none near the target). Then
    ``|omega| <= |h| / x^2``, ``|alpha| <= |alpha_0| + |h| dt / x_min^2``, and
    ``cos^3 sin`` increases up to 30 deg (its maximum, 0.325), so::

        m = 2 h_max^2 / x_min^3 * g(alpha_max),  g(a) = cos^3 sin of min(a, pi/6)

    It stays finite however far a section's states are from the line of sight.
    Bearings are capped at ``MAX_BEARING_RAD`` inside ``cos`` (beyond it the channel
    model -- atan2 bearings, ``x`` for the range -- is void anyway).

    Parameters
    ----------
    w_abs_m, alpha_abs_rad : array
        Per section: largest ``|w|`` (m) and ``|alpha|`` (rad) at the step's start.
    x_min_m, x_max_m : array
        Per section: smallest range over the step (m, > 0) and largest at its start.
    dt_s, e_mps, nu_mps2 : float
        Step, nominal closing speed, the bound of the acceleration across the line
        of sight (the model's ``nu``).

    Returns
    -------
    array
        The margin (m/s^2) to add to ``nu`` for each section.
    """
    # rho <= x_max / cos(MAX_BEARING_RAD): crude, but the nu term is ~1e-4 of h0 or
    # less wherever the margin is not negligible anyway (compiled: one loop)
    w0, a0, x_min, x_max = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (w_abs_m, alpha_abs_rad, x_min_m, x_max_m))
    )
    flat = (np.ravel(v) for v in (w0, a0, x_min, x_max))
    out = kinematic_margin(*flat, float(dt_s), float(e_mps), float(nu_mps2), MAX_BEARING_RAD)
    return out.reshape(w0.shape)


@njit(cache=True)
def _margin1(w0, a0, x_min, x_max, rho_factor, dt, e, max_bearing):
    a = min(abs(a0), max_bearing)
    h = e * abs(w0) / np.cos(a) ** 2 + rho_factor * x_max
    ag = min(a + h * dt / x_min**2, np.pi / 6.0)
    return 2.0 * h * h / x_min**3 * np.cos(ag) ** 3 * np.sin(ag)


@njit(cache=True)
def kinematic_margin(w0, a0, x_min, x_max, dt, e, nu, max_bearing):
    """Elementwise body of :func:`kinematic_margin_mps2` (see there)."""
    n = w0.shape[0]
    out = np.empty(n)
    rho_factor = nu * dt / np.cos(max_bearing)
    for i in range(n):
        out[i] = _margin1(w0[i], a0[i], x_min[i], x_max[i], rho_factor, dt, e, max_bearing)
    return out


@njit(cache=True)
def _g(a):
    # ** 3.0 (a float power, as numpy's ** 3), not repeated multiplication
    return np.cos(a) ** 3.0 * np.sin(a)


@njit(cache=True)
def _interval1(w_lo, w_hi, a_lo, a_hi, x_min, x_max, rho_factor, dt, e, nu, max_bearing):
    w_abs = max(abs(w_lo), abs(w_hi))
    a_abs = max(abs(a_lo), abs(a_hi))
    upper = _margin1(w_abs, a_abs, x_min, x_max, rho_factor, dt, e, max_bearing)
    # the same crude rho bound as the upper bound (rho <= x / cos(max_bearing))
    drift = nu * dt * x_max / np.cos(max_bearing)
    h_max = e * w_abs / np.cos(min(a_abs, max_bearing)) ** 2 + drift
    swing = h_max * dt / x_min**2
    lo_a, hi_a = a_lo - swing, a_hi + swing
    if not (lo_a > 0 or hi_a < 0):
        return -upper, upper
    w_min = min(abs(w_lo), abs(w_hi)) if (w_lo > 0 or w_hi < 0) else 0.0
    h_min = max(e * w_min - drift, 0.0)
    near, far = min(abs(lo_a), abs(hi_a)), min(max(abs(lo_a), abs(hi_a)), 0.5 * np.pi)
    g_min = min(_g(near), _g(far))
    lower = min(2.0 * h_min**2 * g_min / x_max**3.0, upper)
    return (-upper, -lower) if lo_a > 0 else (lower, upper)


@njit(cache=True)
def kinematic_interval(w_lo, w_hi, a_lo, a_hi, x_min, x_max, dt, e, nu, max_bearing):
    """Elementwise body of the signed kinematic interval of a section (tested
    against ``tests/kinematic_reference.py``)."""
    n = w_lo.shape[0]
    lo, hi = np.empty(n), np.empty(n)
    rho_factor = nu * dt / np.cos(max_bearing)
    for i in range(n):
        lo[i], hi[i] = _interval1(
            w_lo[i], w_hi[i], a_lo[i], a_hi[i], x_min[i], x_max[i], rho_factor, dt, e, nu,
            max_bearing,
        )  # fmt: skip
    return lo, hi


@njit(cache=True)
def piece_kinematic(per, u_lo, u_hi, dt, eps, e, nu, max_bearing):
    """The kinematic interval of every piece of a node set from its per-piece bounds
    ``per`` (``w``, ``alpha``, ``tau``), as
    the node set estimator's ``_kinematic`` describes; a piece without cells
    (``tau_lo = inf``) gets zero."""
    n = u_lo.shape[0]
    lo, hi = np.zeros(n), np.zeros(n)
    rho_factor = nu * dt / np.cos(max_bearing)
    for b in range(n):
        if not np.isfinite(per[b, 4]):
            continue
        x_max = max(per[b, 5], 0.0) / u_lo[b]
        x_min = max(min((per[b, 4] - dt) / u_hi[b], x_max), eps)
        lo[b], hi[b] = _interval1(
            per[b, 0], per[b, 1], per[b, 2], per[b, 3], x_min, x_max, rho_factor, dt, e, nu,
            max_bearing,
        )  # fmt: skip
    return lo, hi


def warm_up() -> None:
    """Load the kernels (from numba's on-disk cache, or compile) in this process, with
    the argument kinds they meet (read-only arrays are a numba type of their own)."""
    one, zero = np.ones(1), np.zeros(1)
    for x_max in (one, readonly(one)):
        kinematic_margin(one, zero, one, x_max, 0.5, 1.0, 0.0, 1.5)
    kinematic_interval(one, one, zero, one, one, one, 0.5, 1.0, 0.0, 1.5)
    per = np.ones((1, 6))
    for u in (one, readonly(one)):  # a node set's bands are read-only
        piece_kinematic(per, u, u, 0.5, 1.0, 1.0, 0.0, 1.5)
