"""Guaranteed attitude ellipsoid on the error state, beside the box (docs/models.md §2.5).

The belief of each run is ``S = E ∩ B``: the box ``B`` of
:class:`kalman_vs_infoset.estim.attitude.box.estimator.BoxAttitudeEstimator` (run unchanged) and an
ellipsoid

.. math:: E(c, P) = \\{x : (x - c)^T P^{-1} (x - c) \\le 1\\}
          = \\{c + P^{1/2} u : |u| \\le 1\\} \\subset R^6,

on ``x = (e, w)`` in the box's coordinates, kept as its centre ``c`` and shape matrix
``P`` (symmetric positive definite). The prediction, update and re-centring maps and
their remainders are those of :mod:`estim.attitude.sets.common`; this module gives the
ellipsoid operations, batched over runs (arrays ``(R, 6)`` and ``(R, 6, 6)``), each an
outer bound whatever its free parameter, the parameter choosing only the tightness:

* **box** ``[lo, hi]``: the minimum-volume ellipsoid containing it, centre ``(lo + hi)/2``,
  :math:`P = n\\,\\mathrm{diag}(r^2)`, ``n = 6`` (a corner is on its boundary);
* **affine map plus box** :math:`A E + b \\oplus [-\\rho, \\rho]`: ``A E + b = E(A c + b,
  A P A^T)`` (exact), then the box as the Minkowski sum of its six segments
  :math:`[-\\rho_i, \\rho_i] e_i` in turn (a zero :math:`\\rho_i` is skipped), each by
  Schweppe's (1968) family: for every ``q > 0``

  .. math:: E(c, P) \\oplus [-d, d] \\subset E(c, (1 + q) P + (1 + 1/q)\\, d d^T).

  Minimum volume (Kurzhanski & Valyi 1997; Chernousko 1994): with :math:`L = d^T P^{-1} d`,
  :math:`\\det = (1 + q)^n \\det P\\, (1 + L / q)`, stationary at
  :math:`n q^2 + (n - 1) L q - L = 0`, i.e.
  :math:`q = 2 L / ((n - 1) L + \\sqrt{(n - 1)^2 L^2 + 4 n L})` (:func:`segment_sum`; the
  plane's formula of :func:`kalman_vs_infoset.estim.intercept.sections.ellipsoid.segment_sum` for
  ``n = 2``). Minimum trace: :math:`q = |d| / \\sqrt{\\mathrm{tr} P}`. Then ``P`` gains
  :math:`\\epsilon\\,\\mathrm{diag}(P)`, :math:`\\epsilon = 10^{-12}` (a larger ellipsoid,
  still an outer bound), which keeps it positive definite per axis;
* **axis strip** :math:`lo_i \\le x_i \\le hi_i` (Fogel & Huang 1982): the strip is first
  clipped to the range :math:`c_i \\pm \\sqrt{P_{ii}}` of ``x_i`` over ``E`` (disjoint:
  the run is empty; the whole range: ``E`` unchanged); with ``y`` and ``r`` its centre and
  half-width (``r`` at least :math:`10^{-6} \\sqrt{P_{ii}}`, and wider by a few ulps of
  :math:`|y| + |c_i| + \\sqrt{P_{ii}}`, the rounding of the centres: a wider strip), ``e = y -
  c_i``, ``g = P_{ii}``, ``p = P e_i``, every point of ``E`` in the strip satisfies, for
  every :math:`\\lambda \\ge 0`,
  :math:`(x - c)^T P^{-1} (x - c) + \\lambda (x_i - y)^2 / r^2 \\le 1 + \\lambda`, the
  ellipsoid

  .. math:: c^+ = c + \\frac{\\lambda e}{r^2 + \\lambda g}\\, p, \\qquad
            P^+ = \\delta \\Big(P - \\frac{\\lambda}{r^2 + \\lambda g}\\, p p^T\\Big),
            \\qquad \\delta = 1 + \\lambda - \\frac{\\lambda e^2}{r^2 + \\lambda g}

  (``P^+`` formed in Joseph's form, :func:`strip_update`, which does not cancel when
  the strip is much narrower than ``E``).

  ``criterion="volume"``: Fogel & Huang's minimum of :math:`\\det P^+`, the positive root
  of :math:`(n-1) G^2 \\lambda^2 + G (2n - 1 + \\varepsilon - G) \\lambda + n (1 -
  \\varepsilon) - G` (``G = g/r^2``, :math:`\\varepsilon = e^2/r^2`; 0 when :math:`n (1 -
  \\varepsilon) \\ge G`), as :meth:`estim.common.sets.Ellipsoid.intersect_strip`, in closed form
  and batched. ``criterion="trace"``: their minimum of :math:`\\mathrm{tr} P^+`, among 0
  and the positive roots of a cubic (as
  :func:`estim.common.sets._ellipsoid_weights._trace_rho`), the roots batched as
  companion-matrix eigenvalues (the trace mixes rad² and (rad/s)²: the volume is the
  unit-free choice). Six strips a step, the ``i``-th on the result of the
  previous.

Membership (:meth:`EllipsoidAttitudeBelief.set_inside`) is exact: in the eigenbasis of
the axis-scaled shape ``S^-1 P S^-1 = V \\Lambda V^T`` (``S = diag(sqrt(P_ii))``: the
state mixes rad and rad/s, :func:`scaled_eig`), :math:`\\sqrt{\\sum_k z_k^2 /
\\lambda_k} \\le 1 + tol/\\sqrt{\\lambda_{max}(P)}`, ``z = V^T S^-1 (x - c)``, i.e.
within ``tol`` of ``E`` at most (the absolute ``tol`` of the box's test), directions of
a vanishing eigenvalue (none when the remainders inflate, as they do) being held to a
length ``|z_k| |S v_k| <= tol``.

**Tightness.** An ellipsoid around a box-shaped set is wide on the axes (about
:math:`\\sqrt{6}` times the box for the smallest one around a 6-D box), and the data are
axis-aligned boxes: on the reaction-wheel test of ``tests/test_attitude_sets.py`` the hull
of ``E`` is 2.4 to 3.2 times the box's on every axis and ``S = E ∩ B`` is the box. ``E``
pays where the attitude-rate correlation is strong against the data, e.g. rates measured
far more coarsely than the attitude tells them (there, rate hulls ~1 % narrower on
average, up to 6 %).

References
----------
Schweppe (1968), Fogel & Huang (1982), Chernousko (1994), Kurzhanski & Valyi (1997):
full entries in :mod:`kalman_vs_infoset.estim.common.sets.ellipsoid` and docs/references.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import numpy as np
from kalman_vs_infoset.estim.attitude.box.estimator import BoxAttitudeBelief
from kalman_vs_infoset.estim.attitude.sets.common import (
    FloatArray,
    SetAttitudeBelief,
    SetAttitudeEstimator,
)
from kalman_vs_infoset.estim.attitude.sets.options import ELLIPSOID
from kalman_vs_infoset.estim.common.sets._ellipsoid_weights import volume_weights
from numpy.typing import NDArray

N = 6
Criterion = Literal["volume", "trace"]
#: relative per-axis regularisation after a Minkowski sum, ``P += eps diag(P)``
REGULARISATION = 1e-12
#: relative widening of the computed range of ``x_i`` over ``E`` before clipping a strip
RANGE_INFLATION = 1e-12
#: least strip half-width relative to ``sqrt(P_ii)`` (a wider strip: an outer bound)
MIN_STRIP = 1e-6
#: a strip's half-width grows by this many ulps of ``|y| + |c_i| + sqrt(P_ii)``
STRIP_ROUNDING = 4.0
EPS = float(np.finfo(float).eps)


def ellipsoid_from_box(lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(c, P)``: the minimum-volume ellipsoid of the box, :math:`P = n\\,\\mathrm{diag}(r^2)`."""
    r = 0.5 * (hi - lo)
    n = lo.shape[-1]
    return 0.5 * (lo + hi), n * (r * r)[..., :, None] * np.eye(n)


def ellipsoid_radius(p: FloatArray) -> FloatArray:
    """Per-axis radius of the interval hull: :math:`\\sqrt{P_{ii}}`."""
    return np.sqrt(np.clip(np.diagonal(p, axis1=-2, axis2=-1), 0.0, None))


def _sym(p: FloatArray) -> FloatArray:
    return 0.5 * (p + np.swapaxes(p, -1, -2))


def segment_q(l_quad: FloatArray, n: int) -> FloatArray:
    """The minimum-volume ``q`` of :math:`(1 + q) P + (1 + 1/q) d d^T` for
    :math:`L = d^T P^{-1} d > 0`: the positive root of :math:`n q^2 + (n - 1) L q - L`
    (stable form; ``L = inf`` gives its limit ``1/(n - 1)``)."""
    big = ~np.isfinite(l_quad)
    ell = np.where(big, 1.0, l_quad)
    q = 2.0 * ell / ((n - 1) * ell + np.sqrt((n - 1) ** 2 * ell * ell + 4.0 * n * ell))
    return np.where(big, 1.0 / (n - 1), q)


def segment_sum(p: FloatArray, d: FloatArray, criterion: Criterion = "volume") -> FloatArray:
    """Shape ``(R, n, n)`` of an ellipsoid containing :math:`E(0, P) \\oplus [-d, d]` per run
    (Schweppe's family, minimum volume or trace, closed form; ``d = 0``: unchanged)."""
    n = p.shape[-1]
    t2 = np.sum(d * d, axis=-1)
    t1 = np.trace(p, axis1=-2, axis2=-1)
    live = (t2 > 0.0) & (t1 > 0.0)
    if criterion == "volume":
        try:
            sol = np.linalg.solve(p, d[..., None])[..., 0]
            l_quad = np.sum(d * sol, axis=-1)
            l_quad = np.where(np.isfinite(l_quad) & (l_quad > 0.0), l_quad, np.inf)
        except np.linalg.LinAlgError:  # a singular P: the limit member (still outer)
            l_quad = np.full(t1.shape, np.inf)
        q = segment_q(np.where(live, l_quad, 1.0), n)
    else:
        q = np.sqrt(np.where(live, t2, 1.0) / np.where(live, t1, 1.0))
    dd = d[..., :, None] * d[..., None, :]
    out = (1.0 + q)[..., None, None] * p + (1.0 + 1.0 / q)[..., None, None] * dd
    out = np.where((t1 <= 0.0)[..., None, None], p + dd, out)  # a point: the segment
    return _sym(np.where((t2 <= 0.0)[..., None, None], p, out))


def affine_plus_box(c, p, A, b, rho, criterion: Criterion = "volume"):
    """An ellipsoid ``(c', P')`` containing :math:`A E + b \\oplus [-\\rho, \\rho]`:
    the exact image, six segment sums, the per-axis regularisation (module docstring)."""
    c = np.einsum("rij,rj->ri", A, c) + b
    p = _sym(A @ p @ np.swapaxes(A, -1, -2))
    n = c.shape[-1]
    for i in range(n):
        d = np.zeros_like(c)
        d[:, i] = rho[:, i]
        p = segment_sum(p, d, criterion)
    diag = np.clip(np.diagonal(p, axis1=-2, axis2=-1), 0.0, None)
    return c, p + REGULARISATION * diag[..., :, None] * np.eye(n)


def strip_weight(g, e, r, tr, m2, n: int, criterion: Criterion = "volume") -> FloatArray:
    """The weight :math:`\\lambda \\ge 0` of the strip update (module docstring), batched:
    ``g = P_ii``, ``e`` the strip centre's offset, ``r`` its half-width (> 0), ``tr = tr P``,
    ``m2 = |P e_i|^2``."""
    big_g, eps = g / (r * r), e * e / (r * r)
    vol = volume_weights(n, big_g, eps)
    if criterion == "volume":
        return vol
    # tr P+ = (n3 l^3 + n2 l^2 + n1 l + n0) / (1 + G l)^2; stationary: the cubic below
    mn = m2 / (r * r)
    b1 = tr * big_g - mn
    n3, n0 = big_g * b1, tr
    n2, n1 = big_g * tr + (1.0 + big_g - eps) * b1, (1.0 + big_g - eps) * tr + b1
    c3, c2, c1, c0 = big_g * n3, 3.0 * n3, 2.0 * n2 - big_g * n1, n1 - 2.0 * big_g * n0
    ok = c3 > 0.0
    c3s = np.where(ok, c3, 1.0)
    comp = np.zeros(g.shape + (3, 3))
    comp[..., 0, 0], comp[..., 0, 1], comp[..., 0, 2] = -c2 / c3s, -c1 / c3s, -c0 / c3s
    comp[..., 1, 0] = comp[..., 2, 1] = 1.0
    comp = np.where(ok[..., None, None] & np.isfinite(comp), comp, 0.0)
    roots = np.linalg.eigvals(comp)
    real = np.abs(roots.imag) <= 1e-9 * (1.0 + np.abs(roots))
    cands = np.where(real & (roots.real > 0.0), roots.real, 0.0)
    cands = np.concatenate([np.zeros(g.shape + (1,)), cands], axis=-1)
    size = (((n3[..., None] * cands + n2[..., None]) * cands + n1[..., None]) * cands
            + n0[..., None]) / (1.0 + big_g[..., None] * cands) ** 2  # fmt: skip
    best = np.take_along_axis(cands, np.argmin(size, axis=-1)[..., None], -1)[..., 0]
    return np.where(ok, best, vol)


def strip_update(c, p, i: int, y, r, lam) -> tuple[FloatArray, FloatArray]:
    """Fogel & Huang's member :math:`(c^+, P^+)` of weight ``lam`` for the strip
    :math:`|x_i - y| \\le r` (module docstring; ``lam = 0``: unchanged).

    ``P^+`` is formed in Joseph's form, a sum of two positive semi-definite terms,

    .. math:: P - a\\, p p^T = (I - a\\, p e_i^T) P (I - a\\, p e_i^T)^T
              + a (1 - a g)\\, p p^T, \\qquad a = \\frac{\\lambda}{r^2 + \\lambda g},

    with :math:`1 - a g = r^2 / (r^2 + \\lambda g)` computed as that ratio: for a strip
    much narrower than ``E`` (``lam g >> r^2``) the plain difference cancels, and its
    rounding (``eps g``, against a result near ``r^2``) left points of ``E`` at the
    strip's edge outside ``P^+``."""
    pa = p[:, :, i]
    g = p[:, i, i]
    e = y - c[:, i]
    den = r * r + lam * g
    dens = np.where(den > 0, den, 1.0)
    delta = 1.0 + lam - lam * e * e / dens
    c_new = c + (lam * e / dens)[:, None] * pa
    a = lam / dens
    m = np.broadcast_to(np.eye(p.shape[-1]), p.shape).copy()
    m[:, :, i] -= a[:, None] * pa
    m[:, i, i] = r * r / dens  # 1 - a g, without the cancellation
    rest = a * (r * r / dens)  # a (1 - a g) >= 0
    p_new = delta[:, None, None] * (
        m @ p @ np.swapaxes(m, -1, -2) + rest[:, None, None] * pa[:, :, None] * pa[:, None, :]
    )
    return c_new, _sym(p_new)


def axis_strips(
    c, p, lo, hi, criterion: Criterion = "volume"
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Outer bound of ``E ∩ {lo <= x <= hi}`` by one strip per axis (module docstring);
    ``(c, P, empty)``, empty runs returned unchanged."""
    n = c.shape[-1]
    empty = np.zeros(c.shape[0], dtype=bool)
    for i in range(n):
        g = np.clip(p[:, i, i], 0.0, None)
        half = np.sqrt(g) * (1.0 + RANGE_INFLATION)
        mid = c[:, i]
        a, b = np.maximum(lo[:, i], mid - half), np.minimum(hi[:, i], mid + half)
        empty |= ~(a <= b)
        cut = (a <= b) & ((a > mid - half) | (b < mid + half)) & (g > 0.0) & ~empty
        y = 0.5 * (a + b)
        r = np.maximum(0.5 * (b - a), MIN_STRIP * np.sqrt(g))
        # wider by the rounding of the strip's centre and of E's (the new centre lands
        # within a few ulps of these; for a narrow strip that is a part of r)
        r = r + STRIP_ROUNDING * EPS * (np.abs(y) + np.abs(mid) + np.sqrt(g))
        rs = np.where(cut, r, 1.0)
        gs = np.where(cut, g, 1.0)
        e = np.where(cut, y - mid, 0.0)
        tr = np.trace(p, axis1=-2, axis2=-1)
        m2 = np.sum(p[:, :, i] ** 2, axis=-1)
        lam = strip_weight(gs, e, rs, tr, m2, n, criterion)
        lam = np.where(cut & np.isfinite(lam), lam, 0.0)
        c, p = strip_update(c, p, i, np.where(cut, y, mid), rs, lam)
    return c, p, empty


#: eigenvalues of the axis-scaled shape (unit diagonal) under this times the largest are
#: rounding: those directions are flat
FLAT_RTOL = 1e-14


def scaled_eig(p: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(s, lam, V, lmax)``: the axes' radii ``s = sqrt(P_ii)`` (1 where 0), the
    eigen-decomposition ``lam, V`` of the axis-scaled shape ``P_ij / (s_i s_j)`` (unit
    diagonal), and the largest eigenvalue ``lmax`` of ``P`` itself, per run.

    The state mixes units (rad and rad/s), and ``P``'s eigenvalues then span the
    squared ratio of the axes' scales: a rate axis a million times narrower than the
    attitude has eigenvalues at 1e-12 of the largest, where the rounding of ``eigh``
    (``eps`` times the largest) is a part in 1e4 of them, and under 1e-14 they would
    read as flat. Scaled to a unit diagonal the eigenvalues are at most ``n``, and only
    the correlations make one small."""
    s = np.sqrt(np.clip(np.diagonal(p, axis1=-2, axis2=-1), 0.0, None))
    s = np.where(s > 0.0, s, 1.0)
    lam, vec = np.linalg.eigh(_sym(p / (s[..., :, None] * s[..., None, :])))
    lmax = np.linalg.eigvalsh(p)[..., -1]
    return s, np.clip(lam, 0.0, None), vec, np.clip(lmax, 0.0, None)


def ellipsoid_inside(c, eig, d, tol: float) -> NDArray[np.bool_]:
    """Per run: whether ``c + d`` is in ``E`` given ``eig`` (:func:`scaled_eig` of
    ``P``): :math:`\\sqrt{\\sum_k z_k^2 / \\lambda_k} \\le 1 + tol / \\sqrt{\\lambda_{max}(P)}`
    with ``z = V^T (d / s)`` (the quadratic form is the same in scaled axes), and a
    flat direction ``k`` held to ``|z_k| |s * v_k| <= tol`` (its length in the state's
    units)."""
    s, lam, vec, lmax = eig
    z = np.einsum("rji,rj->ri", vec, d / s)
    top = np.max(lam, axis=-1, keepdims=True)
    pos = lam > FLAT_RTOL * np.maximum(top, 1e-300)
    quad = np.sum(np.where(pos, z * z / np.where(pos, lam, 1.0), 0.0), axis=-1)
    length = np.linalg.norm(s[..., :, None] * vec, axis=-2)  # |s * v_k|, per direction
    flat_ok = np.all(pos | (np.abs(z) * length <= tol), axis=-1)
    return (np.sqrt(quad) <= 1.0 + tol / np.sqrt(np.maximum(lmax, 1e-300))) & flat_ok


@dataclass(frozen=True, eq=False)
class EllipsoidAttitudeBelief(SetAttitudeBelief):
    """``E ∩ B``: the box belief ``box``, ellipsoid centre ``z_c`` ``(R, 6)`` and shape
    matrix ``z_m`` ``(R, 6, 6)``; ``n_empty``/``last_empty`` as the box's (module docstring)."""

    def set_radius(self) -> FloatArray:
        return ellipsoid_radius(self.z_m)

    @cached_property
    def _eig(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        return scaled_eig(_sym(np.nan_to_num(self.z_m)))

    def set_inside(self, d: FloatArray, tol: float) -> NDArray[np.bool_]:
        return ellipsoid_inside(self.z_c, self._eig, d, tol)


@dataclass(frozen=True)
class EllipsoidAttitudeEstimator(SetAttitudeEstimator):
    """Guaranteed ellipsoid of attitude and rate intersected with the box (module docstring).

    Parameters
    ----------
    model : AttitudeModel
    abs_inflation_rad : float
        Absolute inflation per step, rad and rad/s (the box's).
    picard_iterations : int
        Iterations of the Picard inclusion (the box's).
    criterion : {"volume", "trace"}
        Member of the strip (Fogel & Huang) and Minkowski-sum (Schweppe) families:
        minimum volume (unit-free) or minimum trace.
    """

    criterion: Criterion = ELLIPSOID.criterion

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.criterion not in ("volume", "trace"):
            raise ValueError("criterion must be 'volume' or 'trace'")

    def _belief(self, box: BoxAttitudeBelief, z_c, z_m, **kw: Any) -> EllipsoidAttitudeBelief:
        return EllipsoidAttitudeBelief(box, z_c, z_m, **kw)

    def from_box(self, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        return ellipsoid_from_box(lo, hi)

    def radius(self, z_m: FloatArray) -> FloatArray:
        return ellipsoid_radius(z_m)

    def affine(self, z_c, z_m, A, b, rho) -> tuple[FloatArray, FloatArray]:
        return affine_plus_box(z_c, z_m, A, b, rho, self.criterion)

    def strips(self, z_c, z_m, lo, hi) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
        return axis_strips(z_c, z_m, lo, hi, self.criterion)
