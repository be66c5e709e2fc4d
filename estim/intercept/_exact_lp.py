"""Assembly of the linear programs of :mod:`kalman_vs_infoset.estim.intercept.exact_reference` (one
channel).

Variables ``z = (Y_0 .. Y_{n-1}, V_0 .. V_{n-1}, u_0 .. u_{n-2})``: position and
velocity at every history time (before its impulse) and the disturbance ``v_j = nu
u_j``, ``|u_j| <= 1``, constant over ``[t_j, t_j+1]``. The dynamics are sparse
equalities (the same matrix for every LP)::

    Y_{j+1} = Y_j + (V_j + k_j) dt_j + nu dt_j^2 / 2 u_j,   V_{j+1} = V_j + k_j + nu dt_j u_j

and ``x_i = x0 - e t_i = s - e (t_i - t_last)`` with ``s`` the range at the last time.
A bearing is ``|Y_i - alpha_m,i x_i| <= g(x_i) = a(x_i) x_i``,
``g(x) = end x + kappa x^2`` with ``kappa = (start - end) / ref <= 0``: concave, below
each of its tangents ``beta + gamma x``.

* At fixed ``(x0, e)`` a bearing is a bound on ``Y_i``: the LP has no inequality rows.
* On a cell of ``(s, e)`` (outer): two more variables ``X, E`` with ``s = sc +
  X_UNIT_M X``, ``e = ec + E``; ``+-(Y_i - alpha_i x_i) <= beta + gamma x_i`` for each
  tangent, and the a-priori range ``x_0 in [x_lo, x_hi]``, the threshold ``x_last >=
  eps`` and the ranges ``d/(1+b) <= x_i <= d/(1-b)`` are rows in ``(Y_i, X, E)``.
* Kelley's cutting planes (:meth:`ChannelLP.kelley`): a linear function of ``(s, e)``
  is minimised with tangents at the middle of each ``x_i`` range, then with tangents
  added at the solution's ``x_i`` where it violates a bearing, until it violates none
  (to ``VIOLATION_TOL_M``): an outer optimum of the exact set, to that tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from kalman_vs_infoset.estim.intercept.model import ChannelModel
from numpy.typing import NDArray

from kalman_vs_infoset.numerics.lp import NUMERICAL, LinearProgramFailed, linprog_highs

FloatArray = NDArray[np.float64]
X_UNIT_M = 1e3  # s is an LP variable in km (column scaling)
#: a bearing constraint violated by less than this (m) counts as satisfied (Kelley)
VIOLATION_TOL_M = 1e-6


@dataclass(frozen=True)
class Cell:
    """A box of ``(s, e)``: range at the last time (m) and closing speed (m/s)."""

    s: tuple[float, float]
    e: tuple[float, float]

    def corners(self) -> list[tuple[float, float]]:
        return [(s, e) for s in sorted(set(self.s)) for e in sorted(set(self.e))]

    def centre(self) -> tuple[float, float]:
        return 0.5 * (self.s[0] + self.s[1]), 0.5 * (self.e[0] + self.e[1])


@dataclass(frozen=True)
class ChannelLP:
    """The constant parts of the LPs of one channel (module docstring)."""

    model: ChannelModel
    y_m: tuple[float, float]
    v_mps: tuple[float, float]
    x_m: tuple[float, float]
    e_mps: tuple[float, float]
    times_s: FloatArray
    bearings_rad: FloatArray
    impulses_mps: FloatArray
    ranges_m: FloatArray
    t: FloatArray = field(init=False, repr=False)
    n_lp: list[int] = field(init=False, repr=False)  # LPs solved (a counter)
    # derived in __post_init__ from the fields above (not compared: equal when they are)
    tau: FloatArray = field(init=False, repr=False, compare=False)
    a_eq: Any = field(init=False, repr=False, compare=False)  # scipy.sparse CSR, untyped
    b_eq: FloatArray = field(init=False, repr=False, compare=False)
    kappa: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        t = self.times_s - self.times_s[0]
        n, dt, nu, k = len(t), np.diff(self.times_s), self.model.nu_mps2, self.impulses_mps
        j = np.arange(n - 1)
        iy, iv, iu = j, n + j, 2 * n + j
        r_y, r_v = j, n - 1 + j  # one row per step and variable
        rows = np.concatenate([r_y, r_y, r_y, r_y, r_v, r_v, r_v])
        cols = np.concatenate([iy + 1, iy, iv, iu, iv + 1, iv, iu])
        vals = np.concatenate(
            [np.ones(n - 1), -np.ones(n - 1), -dt, -nu * dt**2 / 2, np.ones(n - 1),
             -np.ones(n - 1), -nu * dt]
        )  # fmt: skip
        a_eq = sp.csr_matrix((vals, (rows, cols)), shape=(2 * (n - 1), 3 * n - 1))
        bb = self.model.bearing_bound
        for name, value in (
            ("t", t),
            ("tau", t - t[-1]),
            ("n_lp", [0]),
            ("a_eq", a_eq),
            ("b_eq", np.concatenate([k[:-1] * dt, k[:-1]])),
            ("kappa", (bb.start_rad - bb.end_rad) / bb.ref_range_m),
        ):
            object.__setattr__(self, name, value)

    @property
    def n(self) -> int:
        return len(self.t)

    @property
    def n_z(self) -> int:
        return 3 * self.n - 1

    def g(self, x: FloatArray) -> FloatArray:
        """``g(x) = a(x) x`` (m)."""
        return self.model.bearing_bound.end_rad * x + self.kappa * x**2

    def tangent(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(beta, gamma)`` of the tangent ``beta + gamma x >= g(x)`` at ``xbar``."""
        return -self.kappa * xbar**2, self.model.bearing_bound.end_rad + 2 * self.kappa * xbar

    def split(self, z: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(Y_i, V_i, v_j)`` of a solution (m, m/s, m/s^2)."""
        n = self.n
        return z[:n], z[n : 2 * n], self.model.nu_mps2 * z[2 * n : 3 * n - 1]

    def objective_row(self, a: float, b: float) -> FloatArray:
        """``row . z = a Y_last + b V_last``."""
        row = np.zeros(self.n_z)
        row[self.n - 1], row[2 * self.n - 1] = a, b
        return row

    def violation(self, z: FloatArray, x: FloatArray) -> FloatArray:
        """``|Y_i - alpha_i x_i| - g(x_i)`` (m; positive: bearing ``i`` violated)."""
        return np.abs(z[: self.n] - self.bearings_rad * x) - self.g(x)

    def admissible(self, x0: float, e: float, x: FloatArray) -> bool:
        """The box's ``x0`` and ``e``, the threshold and the range measurements."""
        d, b = self.ranges_m, self.model.range_rel_bound
        has = np.isfinite(d)
        return bool(
            self.x_m[0] <= x0 <= self.x_m[1]
            and self.e_mps[0] <= e <= self.e_mps[1]
            and x[-1] >= self.model.eps_m
            and np.all(x[has] >= d[has] / (1 + b))
            and np.all(x[has] <= d[has] / (1 - b))
        )

    def bounds(self, y_lo: FloatArray, y_hi: FloatArray) -> list[tuple]:
        """Variable bounds with ``Y_i`` in ``[y_lo_i, y_hi_i]`` and the box at ``t_0``."""
        lo, hi = np.array(y_lo, float), np.array(y_hi, float)
        lo[0], hi[0] = max(lo[0], self.y_m[0]), min(hi[0], self.y_m[1])
        v = [self.v_mps] + [(None, None)] * (self.n - 1)
        return list(zip(lo, hi, strict=True)) + v + [(-1.0, 1.0)] * (self.n - 1)

    def fixed_bounds(self, x: FloatArray) -> list[tuple] | None:
        """Bounds at fixed ranges ``x_i`` (bearings as bounds on ``Y_i``); ``None`` when
        a bound is empty."""
        g, centre = self.g(x), self.bearings_rad * x
        out = self.bounds(centre - g, centre + g)
        return None if out[0][0] > out[0][1] or np.any(g < 0) else out

    def relaxed(self, s: tuple, e: tuple, tangents: list[tuple[NDArray, FloatArray]]):
        """Outer constraints on the cell ``s x e`` with ``g`` replaced by its tangents
        at the ``(index, x_bar)`` pairs: ``(A_ub, b_ub, A_eq, b_eq, bounds, (sc, ec))``."""
        tau, alpha, n, nz = self.tau, self.bearings_rad, self.n, self.n_z
        sc, ec = 0.5 * (s[0] + s[1]), 0.5 * (e[0] + e[1])
        base = sc - ec * tau  # x_i = base_i + X_UNIT_M X - tau_i E
        # pieces of a COO matrix: index arrays or short lists, concatenated below
        rows: list[Any] = []
        cols: list[Any] = []
        vals: list[Any] = []
        rhs: list[Any] = []
        r0 = 0
        for idx, xbar in tangents:
            beta, gam = self.tangent(xbar)
            for sg, slope in ((1.0, alpha[idx] + gam), (-1.0, alpha[idx] - gam)):
                r = r0 + np.arange(len(idx))
                rows += [r, r, r]
                cols += [idx, np.full(len(idx), nz), np.full(len(idx), nz + 1)]
                vals += [np.full(len(idx), sg), -sg * slope * X_UNIT_M, sg * slope * tau[idx]]
                rhs.append(beta + sg * slope * base[idx])
                r0 += len(idx)
        # rows sg x_i <= r: the a-priori x_0, the threshold x_last >= eps, the ranges
        d, b = self.ranges_m, self.model.range_rel_bound
        has = np.flatnonzero(np.isfinite(d))
        lin: list[tuple[int, float, float]] = [
            (0, 1.0, self.x_m[1]), (0, -1.0, -self.x_m[0]), (n - 1, -1.0, -self.model.eps_m)
        ]  # fmt: skip
        lin += [(int(i), 1.0, d[i] / (1 - b)) for i in has]
        lin += [(int(i), -1.0, -d[i] / (1 + b)) for i in has]
        for i, sg, r_i in lin:
            rows += [[r0, r0]]
            cols += [[nz, nz + 1]]
            vals += [[sg * X_UNIT_M, -sg * tau[i]]]
            rhs.append([r_i - sg * base[i]])
            r0 += 1
        a_ub = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(r0, nz + 2),
        )
        a_eq = sp.hstack([self.a_eq, sp.csr_matrix((self.a_eq.shape[0], 2))]).tocsr()
        bounds = self.bounds(np.full(n, -np.inf), np.full(n, np.inf)) + [
            ((s[0] - sc) / X_UNIT_M, (s[1] - sc) / X_UNIT_M),
            (e[0] - ec, e[1] - ec),
        ]
        return a_ub, np.concatenate(rhs), a_eq, self.b_eq, bounds, (sc, ec)

    # -- solving -----------------------------------------------------------------------
    def solve(self, c, bounds, a_ub=None, b_ub=None, a_eq=None, b_eq=None):
        """HiGHS (:func:`~kalman_vs_infoset.numerics.lp.linprog_highs`); the dynamics by
        default. The result, or ``None`` when the program is infeasible (an empty cell):
        a verdict of infeasibility is tried again by the other methods too, since a
        wrong one would shrink the reference and let a set that is too small pass."""
        self.n_lp[0] += 1
        a_eq = self.a_eq if a_eq is None else a_eq
        b_eq = self.b_eq if b_eq is None else b_eq
        res = linprog_highs(
            c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds, retry=(*NUMERICAL, 2)
        )
        if res.status in NUMERICAL:  # no method solved it: not an empty cell
            raise LinearProgramFailed(f"the exact set's linear program failed: {res.message}")
        return res if res.status == 0 else None

    def x0(self, s_m: float, e_mps: float) -> tuple[float, float]:
        """``(x0, e)`` of a point ``(s, e)``: ``x0 = s + e t_last``."""
        return float(s_m + e_mps * self.t[-1]), float(e_mps)

    def box_cell(self, e: tuple[float, float] | None = None) -> Cell:
        """The a-priori box (``e`` in ``e``, default the box's) as a cell of ``(s, e)``."""
        (x_lo, x_hi), e, tk = self.x_m, e or self.e_mps, float(self.t[-1])
        return Cell((x_lo - e[1] * tk, x_hi - e[0] * tk), e)

    def mid_tangents(self, cell: Cell) -> list[tuple[NDArray, FloatArray]]:
        """Tangents of ``g`` at the middle of each ``x_i``'s range over the cell."""
        sc, ec = cell.centre()  # x_i = s - e tau_i is affine: its middle at the centre
        return [(np.arange(self.n), sc - ec * self.tau)]

    def solve_relaxed(self, cell: Cell, tangents, c_z: FloatArray, c_xe) -> tuple | None:
        """Minimise ``c_z . z + c_xe . (X, E)`` over the cell's outer system:
        ``(z, s, e, |row multipliers|)`` or ``None`` (empty)."""
        a_ub, b_ub, a_eq, b_eq, bounds, (sc, ec) = self.relaxed(cell.s, cell.e, tangents)
        res = self.solve(np.concatenate([c_z, c_xe]), bounds, a_ub, b_ub, a_eq, b_eq)
        if res is None:
            return None
        nz = len(c_z)
        return (
            res.x[:nz],
            sc + X_UNIT_M * res.x[nz],
            ec + res.x[nz + 1],
            np.abs(res.ineqlin.marginals),
        )

    def kelley(self, cell: Cell, c_xe: tuple[float, float], max_iter: int = 40):
        """Minimise ``c_xe . (X, E)`` over the exact set in the cell (module docstring):
        ``(s, e)`` of the outer optimum, or ``None`` when the cell holds no state."""
        tangents, c_z = self.mid_tangents(cell), np.zeros(self.n_z)
        for _ in range(max_iter):
            sol = self.solve_relaxed(cell, tangents, c_z, c_xe)
            if sol is None:
                return None
            z, s, e, _ = sol
            x = s - e * self.tau
            bad = np.flatnonzero(self.violation(z, x) > VIOLATION_TOL_M)
            if bad.size == 0:
                break
            tangents.append((bad, x[bad]))
        return s, e
