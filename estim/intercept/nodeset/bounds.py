"""Sound bounds of a convex body between its exact slices (the node set's geometry).

The node set (:mod:`.estimator`) keeps, per closing-speed piece, exact slices
``P(tau_j)`` of a convex body ``K`` in ``(Y~, V~, tau)`` (scaled lateral position and
velocity, time to go) at a few values ``tau_j`` (the nodes). Between nodes nothing is
stored; what the body can hold there follows from convexity alone:

for a fixed direction ``d`` the support function ``f(tau) = max {d.s : s in P(tau)}``
of the slices of a convex body is *concave* in ``tau`` (``-inf`` where the slice is
empty). A concave function lies below every secant line outside the secant's own
interval, so on the cell ``[tau_i, tau_i+1]``::

    f(tau) <= L_left(tau)   = f_i   + (f_i   - f_i-1) (tau - tau_i)   / (tau_i   - tau_i-1)
    f(tau) <= L_right(tau)  = f_i+1 + (f_i+1 - f_i+2) (tau_i+1 - tau) / (tau_i+2 - tau_i+1)

whenever the nodes named are not empty; any node beyond ``i`` may stand for ``i-1``
(and beyond ``i+1`` for ``i+2``), and the bounds take one at least 1e-5 of the
extension's reach away (``_geometry.MAX_SECANT_REACH``: a slope through two nodes
closer than that carries their rounding, amplified). The bound is exact at the nodes
and tight wherever ``f`` is nearly linear between them; it needs three live nodes in a row,
which the estimator keeps by refining the nodes. A cell with both ends empty holds
nothing (the live nodes lie elsewhere and the feasible ``tau`` form an interval).

Node polygons are stored in the scaled coordinates ``(a, zs)`` of the estimator:
``a = alpha / alpha_scale`` (bearing) and ``zs = e_nom z`` (the scaled zero-effort
miss ``z = Y~ + V~ tau`` times the nominal closing speed: metres of zero-effort miss
for ``e = e_nom``). At ``tau`` they map linearly to ``(Y~, V~) = (alpha tau,
zs / (e_nom tau) - alpha)``, so a direction ``d = (p, q)`` of ``(Y~, V~)`` reads, on a
vertex of node ``j``, ``d.s = a alpha_scale (p tau_j - q) + zs q / (e_nom tau_j)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.estim.intercept.nodeset._kernels import BEARING, IMPULSE, PREDICT, RANGE
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: relative safety margin on every bound (rounding of the node polygons and of the
#: secant arithmetic; the strips are already rounded outward by 1e-9)
BOUND_RTOL = 1.0e-8


@dataclass(frozen=True, eq=False)
class OpLog:
    """The operations applied to a node set since its initial set, as arrays (the
    compiled :func:`~._kernels.apply_ops` replays them on new nodes).

    ``kinds[o]`` is ``BEARING`` (``pa`` = measured bearing, rad), ``IMPULSE``
    (``q_lo, q_hi`` = interval of the ``V~`` increment per piece), ``RANGE`` (``pa, pb``
    = interval of ``x``, m) or ``PREDICT`` (``pa`` = step, s; ``q_hi`` = bound of
    ``v u`` per piece).
    """

    kinds: NDArray[np.int64]
    pa: FloatArray
    pb: FloatArray
    q_lo: FloatArray
    q_hi: FloatArray
    #: spare rows behind the arrays (which are views of it), shared by the logs that
    #: are prefixes of one another: appending writes in place when this log is the
    #: longest written so far, so a step's append does not copy the whole log
    _spare: _Spare | None = field(default=None, repr=False, compare=False)

    @classmethod
    def empty(cls, n_pieces: int) -> OpLog:
        z = np.zeros(0)
        return cls(np.zeros(0, np.int64), z, z, np.zeros((0, n_pieces)), np.zeros((0, n_pieces)))

    @staticmethod
    def one(kind: int, n_pieces: int, pa=0.0, pb=0.0, q_lo=None, q_hi=None) -> OpLog:
        """A log of one operation."""
        zeros = np.zeros((1, n_pieces))
        return OpLog(
            np.array([kind], np.int64), np.array([float(pa)]), np.array([float(pb)]),
            zeros if q_lo is None else np.asarray(q_lo, float).reshape(1, -1),
            zeros if q_hi is None else np.asarray(q_hi, float).reshape(1, -1),
        )  # fmt: skip

    def __len__(self) -> int:
        return len(self.kinds)

    def __add__(self, other: OpLog) -> OpLog:
        n, k = len(self), len(other)
        spare = self._spare
        if (
            spare is not None
            and spare.fill == n
            and n + k <= len(spare.arrays[0])
            and spare.arrays[3].shape[1:] == other.q_lo.shape[1:]
        ):
            # rows below ``fill`` are never written again: every log sharing the
            # buffer sees only its own prefix, unchanged
            for buf, b in zip(spare.arrays, other.parts(), strict=True):
                buf[n : n + k] = b
        elif n < 32:  # a short log (one step's operations): concatenated
            kinds, pa, pb, q_lo, q_hi = (
                np.concatenate([a, b]) for a, b in zip(self.parts(), other.parts(), strict=True)
            )
            return OpLog(kinds, pa, pb, q_lo, q_hi)
        else:
            cap = 2 * (n + k)
            arrays = tuple(np.empty((cap, *a.shape[1:]), dtype=a.dtype) for a in self.parts())
            for buf, a, b in zip(arrays, self.parts(), other.parts(), strict=True):
                buf[:n], buf[n : n + k] = a, b
            spare = _Spare(arrays)
        spare.fill = n + k
        kinds, pa, pb, q_lo, q_hi = (buf[: n + k] for buf in spare.arrays)
        return OpLog(kinds, pa, pb, q_lo, q_hi, _spare=spare)

    def with_copied_column(self, p: int) -> OpLog:
        """The log with piece ``p``'s parameters copied into a new last column (a
        piece split in two keeps its history in both halves)."""
        # C order, as every other log (the compiled replay has one type per layout)
        return OpLog(
            self.kinds, self.pa, self.pb,
            np.concatenate([self.q_lo, self.q_lo[:, p : p + 1]], axis=1),
            np.concatenate([self.q_hi, self.q_hi[:, p : p + 1]], axis=1),
        )  # fmt: skip

    def parts(self) -> tuple:
        return self.kinds, self.pa, self.pb, self.q_lo, self.q_hi


class _Spare:
    """The growing buffers behind :class:`OpLog` (mutable, private to it)."""

    __slots__ = ("arrays", "fill")

    def __init__(self, arrays: tuple) -> None:
        self.arrays = arrays
        self.fill = 0


__all__ = ["BEARING", "IMPULSE", "PREDICT", "RANGE", "BOUND_RTOL", "OpLog"]
