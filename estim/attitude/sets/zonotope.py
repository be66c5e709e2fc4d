"""Guaranteed attitude zonotope on the error state, beside the box (docs/models.md §2.5).

The belief of each run is ``S = Z ∩ B``: the box ``B`` of
:class:`kalman_vs_infoset.estim.attitude.box.estimator.BoxAttitudeEstimator` (run unchanged) and a
zonotope

.. math:: Z = \\{z_c + G \\xi : \\|\\xi\\|_\\infty \\le 1\\} \\subset R^6,
          \\qquad G \\in R^{6 \\times m},

on ``x = (e, w)`` in the box's coordinates. The prediction, update and re-centring maps
and their remainders are those of :mod:`estim.attitude.sets.common`; this module gives
the zonotope operations, batched over runs (arrays ``(R, 6)`` and ``(R, 6, m)``):

* **affine map plus box** (exact): :math:`A Z + b \\oplus [-\\rho, \\rho] = Z(A z_c + b,
  [A G, \\mathrm{diag}(\\rho)])`;
* **axis strip** :math:`lo_i \\le x_i \\le hi_i` (Alamo, Bravo & Camacho 2005): the strip
  is first clipped to the range :math:`z_{c,i} \\pm \\sum_j |G_{ij}|` of ``x_i`` over
  ``Z`` (disjoint: the run is empty); with ``y`` and ``s`` its centre and half-width,
  for any :math:`\\lambda \\in R^6`

  .. math:: Z \\cap S \\subset Z(z_c + \\lambda (y - z_{c,i}),\\;
            [(I - \\lambda e_i^T) G,\\; s \\lambda]),

  with the choice of least Frobenius norm of the new generators,
  :math:`\\lambda = G g / (g^T g + s^2)`, :math:`g = G^T e_i` (the row ``i`` of ``G``).
  A strip that does not cut leaves ``Z`` as it is (:math:`\\lambda = 0`). Six strips a
  step, the ``i``-th one on the result of the previous;
* **order reduction** (Girard 2005): of the ``M > m`` generators the ``M - m + 6`` with
  the smallest :math:`\\|g\\|_1 - \\|g\\|_\\infty` are replaced by the six generators of
  their interval hull :math:`\\mathrm{diag}(\\sum |g|)`; after every prediction and
  update ``Z`` has ``m = max_generators`` columns (zero columns pad).

Membership (:meth:`ZonotopeAttitudeBelief.inside`) is exact: ``x`` is in ``Z`` iff
:math:`|d^T (x - z_c)| \\le \\sum_j |d^T g_j|` for the unit normals ``d`` of all 5-subsets
of generators (the facet normals when ``Z`` is full-dimensional, which the remainders'
inflation ensures; any other normal gives a valid, redundant inequality); there are
:math:`\\binom{m}{5}` of them (792 for ``m = 12``), computed once per belief.

References
----------
T. Alamo, J. M. Bravo & E. F. Camacho, "Guaranteed state estimation by zonotopes",
Automatica 41(6), 1035-1043, 2005.
A. Girard, "Reachability of uncertain linear systems using zonotopes", HSCC 2005,
LNCS 3414, 291-305.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import combinations
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.box.estimator import BoxAttitudeBelief
from kalman_vs_infoset.estim.attitude.sets.common import (
    FloatArray,
    SetAttitudeBelief,
    SetAttitudeEstimator,
)
from kalman_vs_infoset.estim.attitude.sets.options import ZONOTOPE
from numpy.typing import NDArray

N = 6


def zonotope_radius(g: FloatArray) -> FloatArray:
    """Per-axis radius of the interval hull: :math:`\\sum_j |G_{ij}|`."""
    return np.abs(g).sum(axis=-1)


def affine_plus_box(c, g, A, b, rho) -> tuple[FloatArray, FloatArray]:
    """:math:`A Z + b \\oplus [-\\rho, \\rho]` (exact), ``(R, n)``, ``(R, n, M + n)``."""
    box = rho[..., :, None] * np.eye(c.shape[-1])
    return np.einsum("rij,rj->ri", A, c) + b, np.concatenate([A @ g, box], axis=-1)


def _hull_lambda(g: FloatArray, gi: FloatArray, s: FloatArray) -> FloatArray:
    """The ``lam`` of least interval hull: per row ``j`` the minimiser of
    :math:`\\sum_k |G_{jk} - \\lambda_j g_k| + s |\\lambda_j|`, a weighted median of the
    ratios :math:`G_{jk}/g_k` (weights :math:`|g_k|`) and 0 (weight ``s``)."""
    nz = gi != 0.0
    ratio = np.where(nz[:, None, :], g / np.where(nz, gi, 1.0)[:, None, :], 0.0)
    pts = np.concatenate([ratio, np.zeros(ratio.shape[:-1] + (1,))], axis=-1)
    w = np.concatenate([np.abs(gi), s[:, None]], axis=-1)[:, None, :]
    order = np.argsort(pts, axis=-1)
    cw = np.cumsum(np.take_along_axis(np.broadcast_to(w, pts.shape), order, -1), axis=-1)
    k = np.argmax(cw >= 0.5 * cw[..., -1:], axis=-1)
    return np.take_along_axis(np.take_along_axis(pts, order, -1), k[..., None], -1)[..., 0]


def axis_strips(
    c, g, lo, hi, choice: str = "hull"
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Outer bound of ``Z ∩ {lo <= x <= hi}`` by one strip per axis (module docstring);
    ``(c, G with n more columns, empty)``."""
    empty = np.zeros(c.shape[0], dtype=bool)
    for i in range(c.shape[-1]):
        gi = g[:, i, :]
        half = np.abs(gi).sum(axis=-1)
        mid = c[:, i]
        a, b = np.maximum(lo[:, i], mid - half), np.minimum(hi[:, i], mid + half)
        empty |= a > b
        cut = (a <= b) & ((a > mid - half) | (b < mid + half))
        y, s = 0.5 * (a + b), 0.5 * (b - a)
        if choice == "hull":
            lam = _hull_lambda(g, gi, s)
        else:
            den = np.sum(gi * gi, axis=-1) + s * s
            lam = np.einsum("rjk,rk->rj", g, gi) / np.where(den > 0, den, 1.0)[:, None]
        lam = np.where(cut[:, None], lam, 0.0)
        g = np.concatenate(
            [g - lam[:, :, None] * gi[:, None, :], (s[:, None] * lam)[..., None]], -1
        )
        c = c + lam * np.where(cut, y - mid, 0.0)[:, None]
    return c, g, empty


def reduce_girard(g: FloatArray, m: int) -> FloatArray:
    """At most ``m`` (``>= n``) generators, exactly ``m`` columns (Girard's box method)."""
    runs, n, cols = g.shape
    if cols <= m:
        return np.concatenate([g, np.zeros((runs, n, m - cols))], axis=-1)
    ag = np.abs(g)
    order = np.argsort(ag.sum(axis=1) - ag.max(axis=1), axis=-1, kind="stable")
    n_boxed = cols - m + n
    boxed, kept = order[:, :n_boxed], np.sort(order[:, n_boxed:], axis=-1)
    hull = np.take_along_axis(ag, boxed[:, None, :], axis=2).sum(axis=-1)
    kept_g = np.take_along_axis(g, kept[:, None, :], axis=2)
    return np.concatenate([kept_g, hull[:, :, None] * np.eye(n)], axis=-1)


def facet_normals(g: FloatArray) -> FloatArray:
    """Unit normals ``(R, S, n)`` of all ``(n-1)``-subsets of the columns of ``g``."""
    runs, n, m = g.shape
    subsets = np.array(list(combinations(range(m), n - 1)))
    cols = g[:, :, subsets].transpose(0, 2, 1, 3)  # (R, S, n, n-1)
    # the last column of Q in A = QR is orthogonal to range(A), whatever its rank
    return np.linalg.qr(cols, mode="complete")[0][..., :, -1]


def zonotope_inside(c, g, normals, d, tol: float) -> NDArray[np.bool_]:
    """Per run: whether ``c + d`` is in ``Z(c, G)`` by the facet inequalities."""
    h = np.abs(normals @ g).sum(axis=-1)  # (R, S)
    dist = np.abs(np.einsum("rsj,rj->rs", normals, d)) - h
    return np.all(dist <= tol, axis=-1)


@dataclass(frozen=True, eq=False)
class ZonotopeAttitudeBelief(SetAttitudeBelief):
    """``Z ∩ B``: the box belief ``box``, zonotope centre ``z_c`` ``(R, 6)`` and generators
    ``z_m`` ``(R, 6, m)``; ``n_empty``/``last_empty`` as the box's (module docstring)."""

    def set_radius(self) -> FloatArray:
        return zonotope_radius(self.z_m)

    @cached_property
    def _normals(self) -> FloatArray:
        return facet_normals(self.z_m)

    def set_inside(self, d: FloatArray, tol: float) -> NDArray[np.bool_]:
        return zonotope_inside(self.z_c, self.z_m, self._normals, d, tol)


@dataclass(frozen=True)
class ZonotopeAttitudeEstimator(SetAttitudeEstimator):
    """Guaranteed zonotope of attitude and rate intersected with the box (module docstring).

    Parameters
    ----------
    model : AttitudeModel
    abs_inflation_rad : float
        Absolute inflation per step, rad and rad/s (the box's).
    picard_iterations : int
        Iterations of the Picard inclusion (the box's).
    max_generators : int
        Generators kept after each reduction, 6 to 16 (``binom(m, 5)`` facets for
        membership).
    """

    max_generators: int = ZONOTOPE.max_generators
    strip_choice: str = ZONOTOPE.strip_choice

    def __post_init__(self) -> None:
        super().__post_init__()
        if not N <= self.max_generators <= 16:
            raise ValueError("max_generators must be within 6 and 16")
        if self.strip_choice not in ("hull", "frobenius"):
            raise ValueError("strip_choice must be 'hull' or 'frobenius'")

    def _belief(self, box: BoxAttitudeBelief, z_c, z_m, **kw: Any) -> ZonotopeAttitudeBelief:
        return ZonotopeAttitudeBelief(box, z_c, z_m, **kw)

    def from_box(self, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        g = 0.5 * (hi - lo)[:, :, None] * np.eye(N)
        return 0.5 * (lo + hi), reduce_girard(g, self.max_generators)

    def radius(self, z_m: FloatArray) -> FloatArray:
        return zonotope_radius(z_m)

    def affine(self, z_c, z_m, A, b, rho) -> tuple[FloatArray, FloatArray]:
        c, g = affine_plus_box(z_c, z_m, A, b, rho)
        return c, reduce_girard(g, self.max_generators)

    def strips(self, z_c, z_m, lo, hi) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
        return axis_strips(z_c, z_m, lo, hi, self.strip_choice)
