"""Assembly of the linear programs of :mod:`estim.exact_reference` (one channel).

With ``z = (Y0, V0, u_0 .. u_{n-2})``, ``v_j = nu u_j`` (``|u_j| <= 1``)::

    Y_i = P_i z + K_i,   P_i z = Y0 + V0 t_i + sum_{j<i} nu u_j dt_j (t_i - t_j - dt_j/2),
    K_i = sum_{j<i} k_j (t_i - t_j),   V_last = Q z + L,  L = sum_{j<last} k_j,

and ``x_i = x0 - e t_i``. A bearing is ``|Y_i - alpha_m,i x_i| <= g(x_i) = a(x_i) x_i``,
``g(x) = end x + kappa x^2`` with ``kappa = (start - end) / ref <= 0``: concave, below
each of its tangents ``beta + gamma x``.

* At fixed ``(x0, e)``: ``[P; -P] z <= [alpha x + g - K; -alpha x + g + K]``; the
  matrix is the same for every ``(x0, e)``, only the right-hand side moves.
* On a cell of ``(x0, e)`` (outer): variables ``(z, X, E)`` with ``x0 = xc + X_UNIT_M
  X``, ``e = ec + E``; ``s (Y_i - alpha_i x_i) <= beta + gamma x_i`` for ``s = +-1``
  and each tangent, the threshold ``x_last >= eps`` and the ranges
  ``d/(1+b) <= x_i <= d/(1-b)`` as rows in ``(X, E)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from estim.model import ChannelModel

FloatArray = NDArray[np.float64]
X_UNIT_M = 1e3  # x0 is an LP variable in km (column scaling)


@dataclass(frozen=True)
class ChannelLP:
    """The constant parts of the LPs of one channel (module docstring)."""

    model: ChannelModel
    y_m: tuple[float, float]
    v_mps: tuple[float, float]
    times_s: FloatArray
    bearings_rad: FloatArray
    impulses_mps: FloatArray
    ranges_m: FloatArray
    t: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        t = self.times_s - self.times_s[0]
        n, dt = len(t), np.diff(self.times_s)
        p = np.zeros((n, n + 1))
        p[:, 0], p[:, 1] = 1.0, t
        lag = t[:, None] - t[None, :-1] - 0.5 * dt[None, :]
        p[:, 2:] = np.where(lag > 0, self.model.nu_mps2 * dt[None, :] * lag, 0.0)
        k = self.impulses_mps
        kk = np.where(t[:, None] > t[None, :], (t[:, None] - t[None, :]) * k[None, :], 0.0)
        q = np.zeros(n + 1)
        q[1], q[2:] = 1.0, self.model.nu_mps2 * dt
        bb = self.model.bearing_bound
        for name, value in (
            ("t", t),
            ("p", sp.csr_matrix(p)),
            ("p_last", p[-1].copy()),
            ("k", kk.sum(axis=1)),
            ("q", q),
            ("l", float(k[:-1].sum())),
            ("a_fixed", sp.vstack([sp.csr_matrix(p), -sp.csr_matrix(p)]).tocsr()),
            ("z_bounds", [self.y_m, self.v_mps] + [(-1.0, 1.0)] * (n - 1)),
            ("kappa", (bb.start_rad - bb.end_rad) / bb.ref_range_m),
        ):
            object.__setattr__(self, name, value)

    @property
    def n_z(self) -> int:
        return self.p.shape[1]

    def g(self, x: FloatArray) -> FloatArray:
        """``g(x) = a(x) x`` (m)."""
        return self.model.bearing_bound.end_rad * x + self.kappa * x**2

    def tangent(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(beta, gamma)`` of the tangent ``beta + gamma x >= g(x)`` at ``xbar``."""
        return -self.kappa * xbar**2, self.model.bearing_bound.end_rad + 2 * self.kappa * xbar

    def violation(self, z: FloatArray, x: FloatArray) -> FloatArray:
        """``|Y_i - alpha_i x_i| - g(x_i)`` (m; positive: bearing ``i`` violated)."""
        return np.abs(self.p @ z + self.k - self.bearings_rad * x) - self.g(x)

    def ranges_hold(self, x: FloatArray) -> bool:
        """The threshold and the range measurements at ranges ``x_i``."""
        d, b = self.ranges_m, self.model.range_rel_bound
        has = np.isfinite(d)
        return bool(
            x[-1] >= self.model.eps_m
            and np.all(x[has] >= d[has] / (1 + b))
            and np.all(x[has] <= d[has] / (1 - b))
        )

    def fixed_rhs(self, x: FloatArray) -> FloatArray:
        """Right-hand side of ``a_fixed z <= b`` at ranges ``x_i``."""
        g, alpha = self.g(x), self.bearings_rad
        return np.concatenate([alpha * x + g - self.k, -alpha * x + g + self.k])

    def last_state(self, z: FloatArray) -> tuple[float, float]:
        """``(Y, V)`` at the last time."""
        return float(self.p_last @ z + self.k[-1]), float(self.q @ z + self.l)

    def relaxed(self, x0: tuple, e: tuple, tangents: list[tuple[NDArray, FloatArray]]):
        """Outer constraints on the cell ``x0 x e`` with ``g`` replaced by its tangents
        at the ``(index, x_bar)`` pairs: ``(A_ub, b_ub, bounds, (xc, ec))``."""
        t, alpha = self.t, self.bearings_rad
        xc, ec = 0.5 * (x0[0] + x0[1]), 0.5 * (e[0] + e[1])
        base = xc - ec * t  # x_i = base_i + X_UNIT_M X - t_i E
        blocks, rhs = [], []
        for idx, xbar in tangents:
            beta, gam = self.tangent(xbar)
            for s, slope in ((1.0, alpha[idx] + gam), (-1.0, alpha[idx] - gam)):
                xe = np.column_stack([-s * slope * X_UNIT_M, s * slope * t[idx]])
                blocks.append(sp.hstack([s * self.p[idx], sp.csr_matrix(xe)]))
                rhs.append(beta - s * self.k[idx] + s * slope * base[idx])
        # rows s x_i <= r: the threshold x_last >= eps, then d/(1+b) <= x_i <= d/(1-b)
        d, b = self.ranges_m, self.model.range_rel_bound
        has = np.flatnonzero(np.isfinite(d))
        lin = [(len(t) - 1, -1.0, -self.model.eps_m)]
        lin += [(i, 1.0, d[i] / (1 - b)) for i in has] + [(i, -1.0, -d[i] / (1 + b)) for i in has]
        rows = np.zeros((len(lin), self.n_z + 2))
        for r, (i, s, _) in enumerate(lin):
            rows[r, self.n_z :] = s * X_UNIT_M, -s * t[i]
        rhs.append(np.array([r - s * base[i] for i, s, r in lin]))
        bounds = self.z_bounds + [
            ((x0[0] - xc) / X_UNIT_M, (x0[1] - xc) / X_UNIT_M),
            (e[0] - ec, e[1] - ec),
        ]
        a_ub = sp.vstack([*blocks, sp.csr_matrix(rows)]).tocsr()
        return a_ub, np.concatenate(rhs), bounds, (xc, ec)
