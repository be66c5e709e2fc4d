"""The maps of one step of the attitude sets (:mod:`estim.attitude.sets.common`), each as a
linear part plus a remainder box valid over a hull of the error state ``x = (e, w)``.

**Prediction** over ``dt`` (:func:`predict_map`): the reference moves by ``c``,
:math:`q_{ref}' = q_{ref} \\exp(c)` (the box's choice). Over the hull ``H`` (centre ``h``,
radius ``r``) a Picard enclosure :math:`W^*` of ``w(s)`` and :math:`F(W^*) \\subset
(f_c, f_r)` are computed as in :mod:`estim.attitude.box.estimator`; then for every state in ``H``

.. math::

    e' = R(c)^T e + dt\\, J_r(c)\\,(w - h_w) + \\beta_e, \\qquad
    w' = w + dt\\, F, \\quad F \\in (f_c, f_r),

i.e. :math:`x' \\in A x + b \\oplus [-\\rho, \\rho]`, :math:`A = [[R(c)^T, dt J_r(c)], [0, I]]`.
:math:`\\beta_e` collects: the Magnus increment :math:`\\delta = \\int w - c = dt (w - h_w) +
\\beta`, :math:`\\beta \\in (dt\\, h_w + dt^2/2\\, f_c - c,\\; dt^2/2\\, f_r + |\\rho_M|)`,
:math:`|\\rho_M| \\le |W^*| |F| dt^3/6` (as the box); :math:`\\delta' = \\log(\\exp(-c)
\\exp(c + \\delta)) = J_r(c)\\,\\delta + \\epsilon`, :math:`|\\epsilon_i| \\le |\\delta|^2` (the
box's bound; :math:`J_r` the right Jacobian of SO(3)); and the BCH product
:math:`\\log(\\exp(a)\\exp(\\delta')) = a + \\delta' + \\tfrac12 a \\times \\delta' + R_3`,
:math:`a = R(c)^T e` (conjugation), the cross product enclosed in interval arithmetic
over the hulls, :math:`|R_3| \\le K |a||\\delta'|(|a| + |\\delta'|)`, ``K = 1/4`` (the
box's constant, valid below :math:`|a| + |\\delta'| = 1/2`; beyond, :class:`NoEnclosure`).

**Re-centring** at ``c`` (:func:`recentre_map`), :math:`e' = \\log(\\exp(-c)\\exp(e))`:

.. math:: e' = (I - \\tfrac12 [c]_\\times)\\, e - c + R_3, \\quad |R_3| \\le K |c||e|(|c| + |e|).

Every remainder is inflated as the box's (relative 1e-12 of the image, plus
``abs_inflation_rad`` per step) for rounding and the truth simulators' error.
:func:`meet_measurement` is the box's intersection with the measurement box before it
re-centres.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.attitude.box.estimator import (
    BCH_K,
    BCH_MAX,
    REL_INFLATION,
    BoxAttitudeBelief,
    BoxAttitudeEstimator,
    NoEnclosure,
    icross,
    inorm_max,
)
from kalman_vs_infoset.estim.attitude.model import AttitudeControl
from numpy.typing import NDArray

from kalman_vs_infoset.numerics.rotations import qexp, qmatrix

FloatArray = NDArray[np.float64]
_EYE3 = np.eye(3)


def skew(v: FloatArray) -> FloatArray:
    """``[v]_x`` with ``[v]_x u = v x u``, batched ``(..., 3) -> (..., 3, 3)``."""
    z = np.zeros_like(v[..., 0])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def right_jacobian(c: FloatArray) -> FloatArray:
    """:math:`J_r(c) = I - a [c]_\\times + b [c]_\\times^2`, :math:`a = (1 - \\cos t)/t^2`,
    :math:`b = (t - \\sin t)/t^3`, ``t = |c|`` (series below 1e-3):
    :math:`\\exp(c + \\delta) = \\exp(c)\\exp(J_r(c)\\delta + O(\\delta^2))`."""
    t2 = np.sum(c * c, axis=-1)[..., None, None]
    t = np.sqrt(t2)
    small = t < 1e-3
    ts = np.where(small, 1.0, t)
    a = np.where(small, 0.5 - t2 / 24 + t2 * t2 / 720, (1 - np.cos(ts)) / ts**2)
    b = np.where(small, 1 / 6 - t2 / 120 + t2 * t2 / 5040, (ts - np.sin(ts)) / ts**3)
    k = skew(c)
    return _EYE3 - a * k + b * (k @ k)


def _mv(m: FloatArray, v: FloatArray) -> FloatArray:
    return np.einsum("...ij,...j->...i", m, v)


def inflate(c: FloatArray, r: FloatArray, abs_r: float) -> FloatArray:
    """The box's rounding inflation of a radius ``r`` about ``c``."""
    return r + REL_INFLATION * (np.abs(c) + r) + abs_r


def predict_map(box: BoxAttitudeEstimator, hc, hr, c, ctrl: AttitudeControl, dt_s: float):
    """``(A, b, rho)``: :math:`x' \\in A x + b \\oplus [-\\rho, \\rho]` for every state of the
    hull ``(hc, hr)`` (module docstring), the reference moved by ``c``."""
    runs = hc.shape[0]
    ec, er, wc, wr = hc[:, :3], hr[:, :3], hc[:, 3:], hr[:, 3:]
    (ac, ar), (fc, fr) = box.rate_enclosure(wc, wr, ctrl, dt_s)
    rho_m = inorm_max(ac, ar) * inorm_max(fc, fr) * dt_s**3 / 6
    bc = dt_s * wc + 0.5 * dt_s**2 * fc - c
    br = 0.5 * dt_s**2 * fr + rho_m[:, None]
    dmax = np.linalg.norm(dt_s * wr + np.abs(bc) + br, axis=-1)
    jr = right_jacobian(c)
    rt = np.swapaxes(qmatrix(qexp(c)), -1, -2)
    # delta' = dt J_r (w - wc) + J_r beta + eps, |eps_i| <= |delta|^2
    pc = _mv(jr, bc)
    pr_rem = _mv(np.abs(jr), br) + (dmax * dmax)[:, None]
    pr = _mv(np.abs(jr), dt_s * wr) + pr_rem
    # a = R^T e; 1/2 a x delta' and R3 over the hulls
    a_c, a_r = _mv(rt, ec), _mv(np.abs(rt), er)
    na, nd = inorm_max(a_c, a_r), inorm_max(pc, pr)
    if np.any(na + nd > BCH_MAX):
        raise NoEnclosure
    xc, xr = icross(a_c, a_r, pc, pr)
    r3 = BCH_K * na * nd * (na + nd)
    A = np.zeros((runs, 6, 6))
    A[:, :3, :3], A[:, :3, 3:], A[:, 3:, 3:] = rt, dt_s * jr, _EYE3
    b = np.concatenate([pc - dt_s * _mv(jr, wc) + 0.5 * xc, dt_s * fc], axis=-1)
    rho = np.concatenate([pr_rem + 0.5 * xr + r3[:, None], dt_s * fr], axis=-1)
    return A, b, _inflated(A, b, rho, hc, hr, box.abs_inflation_rad)


def recentre_map(c: FloatArray, hc: FloatArray, hr: FloatArray, abs_r: float = 0.0):
    """``(A, b, rho)`` of :math:`e' = \\log(\\exp(-c)\\exp(e))` over the hull (``w`` unchanged)."""
    runs = c.shape[0]
    nc, ne = np.linalg.norm(c, axis=-1), inorm_max(hc[:, :3], hr[:, :3])
    if np.any(nc + ne > BCH_MAX):
        raise NoEnclosure
    A = np.tile(np.eye(6), (runs, 1, 1))
    A[:, :3, :3] -= 0.5 * skew(c)
    b = np.concatenate([-c, np.zeros_like(c)], axis=-1)
    rho = np.zeros((runs, 6))
    rho[:, :3] = (BCH_K * nc * ne * (nc + ne))[:, None]
    return A, b, _inflated(A, b, rho, hc, hr, abs_r)


def _inflated(A, b, rho, hc, hr, abs_r: float) -> FloatArray:
    """``rho`` plus the rounding inflation of the image of the hull."""
    img_r = _mv(np.abs(A), hr) + rho
    return inflate(_mv(A, hc) + b, img_r, abs_r) - img_r + rho


def meet_measurement(box: BoxAttitudeEstimator, belief: BoxAttitudeBelief, meas):
    """``(lo, hi, empty)`` of the box's update before it re-centres
    (:meth:`BoxAttitudeEstimator.meet`: lost and contradicted runs restarted from the
    measurement's box about the measured attitude, the frame the box's update takes)."""
    _, lo, hi, empty = box.meet(belief, meas)
    return lo, hi, empty
