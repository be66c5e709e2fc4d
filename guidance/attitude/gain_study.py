"""Gain study of the quaternion PD law (seed 001, Figs. 10-15, eqs. (24)-(29); docs/models.md §2.2).

For a rest-to-rest turn about a principal axis with the gyroscopic compensation of
law (6), the motion stays about that axis and (seed eq. (26)) the acceleration
``eps = M_u/J`` does not depend on ``J``::

    phi'' = clip(-k_w phi' - k_q s sin(phi/2))                          (8), (26)

(``s`` = 1 or 2, see :mod:`guidance.attitude.pd`; ``clip`` applies ``|M| <= M_max`` and
the momentum limit ``|phi'| <= L_max/J``, wheels unloaded at rest). The whole gain
grid is simulated as one numpy batch: the controller is sampled every
``control_period_s`` (zero-order hold, 100 Hz by default) and between samples the
constant-acceleration motion is integrated exactly, so the fixed step is exact for
the sampled-data loop. The 3-axis plant gives the same settle times (tested).

Reading of the seed that reproduces its f0 table (``TABLE_READING``): the law with
``2 qbar`` (``quaternion_term="twice"``, ``k_q`` multiplies ~phi) and the turn
started from ``q0 = cos(phi0) + n sin(phi0)`` (eq. (11) without its half angle,
``initial_turn="full_angle"``: the simulated turn is ``2 phi0``), settle criterion
0.01 deg / 0.01 deg/s, gain grid 0.1..3.0 step 0.025, and the parabola (27) fitted
to the efficient-coefficient curve with a robust (soft-L1) loss, because the curve
jumps between branches of local minima (the seed's "lines of local minima",
Fig. 10: one more overshoot inside the tolerance). In the linear regime this is the
same as a ``phi0`` turn with a 0.005 deg / 0.005 deg/s criterion. Every one of
these choices is a parameter of :class:`StudySettings`.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from kalman_vs_infoset.guidance.attitude.pd import (
    ANGLE_TOL_DEG,
    RATE_TOL_DEGPS,
    QuaternionTerm,
    term_scale,
)
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset import data as bundled

FloatArray = NDArray[np.float64]

#: Seed eq. (28), as printed: f0 = c1/phi0^p1 + c2/phi0^p2. It matches the seed's
#: table only with phi0 in radians and divided by 2 (i.e. it is written for the
#: "vector" convention): eq.(28)(1 deg = 0.01745 rad) = 0.684 = 2 x 0.342.
SEED_FIT_EQ28 = {"c1": 0.003543, "p1": 0.755, "c2": 0.5466, "p2": 0.02672}

#: The seed's f0 table (transcribed in the bundled ``reference/f0_table.csv``).
F0_TABLE_CSV = bundled.path("reference", "f0_table.csv")


def load_f0_table(path: str | Path = F0_TABLE_CSV) -> dict[float, float]:
    """The seed's table ``{phi0_deg: f0}`` from the bundled ``reference/f0_table.csv``."""
    out: dict[float, float] = {}
    with Path(path).open(newline="") as fh:
        for row in csv.DictReader(line for line in fh if not line.startswith("#")):
            out[float(row["phi0_deg"])] = float(row["f0"])
    return out


@dataclass(frozen=True)
class StudySettings:
    """Conventions and numerics of the gain study (defaults: the table reading)."""

    quaternion_term: QuaternionTerm = "twice"
    initial_turn: Literal["eq11", "full_angle"] = "full_angle"
    angle_tol_deg: float = ANGLE_TOL_DEG
    rate_tol_degps: float = RATE_TOL_DEGPS
    grid_lo: float = 0.1
    grid_hi: float = 3.0
    grid_step: float = 0.025
    control_period_s: float = 0.01
    horizon_s: float = 60.0
    hold_s: float = 5.0
    fit_loss: Literal["linear", "soft_l1", "cauchy"] = "soft_l1"
    inertia_kgm2: float = 1.5
    torque_max_Nm: float = np.inf
    momentum_max_Nms: float = np.inf

    def __post_init__(self) -> None:
        term_scale(self.quaternion_term)
        if self.initial_turn not in ("eq11", "full_angle"):
            raise ValueError("initial_turn must be 'eq11' or 'full_angle'")
        if self.fit_loss not in ("linear", "soft_l1", "cauchy"):
            raise ValueError("fit_loss must be 'linear', 'soft_l1' or 'cauchy'")
        positive = ("angle_tol_deg", "rate_tol_degps", "grid_step", "control_period_s")
        for name in (*positive, "horizon_s", "inertia_kgm2", "torque_max_Nm", "momentum_max_Nms"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive")
        if not (0 < self.grid_lo < self.grid_hi):
            raise ValueError("need 0 < grid_lo < grid_hi")
        if not 0 <= self.hold_s < self.horizon_s:
            raise ValueError("need 0 <= hold_s < horizon_s")

    def grid(self) -> FloatArray:
        """Gain values ``grid_lo .. grid_hi`` with ``grid_step`` (both ends included)."""
        n = int(np.floor((self.grid_hi - self.grid_lo) / self.grid_step + 1e-9)) + 1
        return np.round(self.grid_lo + self.grid_step * np.arange(n), 10)

    def turn_rad(self, phi0_deg: ArrayLike) -> FloatArray:
        """The simulated turn for a nominal ``phi0`` (doubled with ``"full_angle"``)."""
        factor = 2.0 if self.initial_turn == "full_angle" else 1.0
        return np.radians(np.asarray(phi0_deg, dtype=float)) * factor


#: Seed 001's 150 deg reference case (Fig. 10): literal reading, wheel limits, J = 1.5.
MANEUVER_150 = StudySettings(
    quaternion_term="vector",
    initial_turn="eq11",
    horizon_s=150.0,
    torque_max_Nm=0.0275,
    momentum_max_Nms=0.2,
)


def settle_times(
    phi0_rad: ArrayLike, k_q: ArrayLike, k_w: ArrayLike, settings: StudySettings
) -> FloatArray:
    """Settle times (s) of the single-axis sampled-data loop, one numpy batch.

    ``phi0_rad`` (the simulated turn), ``k_q`` and ``k_w`` broadcast together. A
    case is settled at the first sample from which ``|phi| < angle_tol`` and
    ``|phi'| < rate_tol`` hold up to ``horizon_s``; cases whose settle time exceeds
    ``horizon_s - hold_s`` (no confirmation) are ``inf``.
    """
    shape = np.broadcast_shapes(np.shape(phi0_rad), np.shape(k_q), np.shape(k_w))
    phi = np.array(np.broadcast_to(phi0_rad, shape), dtype=float)
    kw = np.broadcast_to(np.asarray(k_w, dtype=float), shape)
    kqs = np.broadcast_to(
        np.asarray(k_q, dtype=float) * term_scale(settings.quaternion_term), shape
    )
    w = np.zeros(shape)
    dt = settings.control_period_s
    a_max = settings.torque_max_Nm / settings.inertia_kgm2
    w_max = settings.momentum_max_Nms / settings.inertia_kgm2
    tol_a = np.radians(settings.angle_tol_deg)
    tol_r = np.radians(settings.rate_tol_degps)
    n = int(round(settings.horizon_s / dt))
    # the last sample (0 the initial state, i + 1 after period i) that fails the criterion;
    # settled at the next one (-1: the initial state already meets it, settled at 0 s)
    last_bad = np.where((np.abs(phi) >= tol_a) | (np.abs(w) >= tol_r), 0, -1)
    u, tmp = np.empty(shape), np.empty(shape)
    bad, bad2 = np.empty(shape, dtype=bool), np.empty(shape, dtype=bool)
    for i in range(n):
        # eps = -(k_w w + k_q s sin(phi/2)), eq. (26)
        np.multiply(phi, 0.5, out=u)
        np.sin(u, out=u)
        u *= kqs
        np.multiply(kw, w, out=tmp)
        u += tmp
        np.negative(u, out=u)
        if np.isfinite(a_max):
            np.clip(u, -a_max, a_max, out=u)
        if np.isfinite(w_max):  # wheel momentum: |w| <= L_max/J at the end of the period
            np.clip(u, (-w_max - w) / dt, (w_max - w) / dt, out=u)
        # exact motion under constant acceleration over one sample
        np.multiply(u, 0.5 * dt, out=tmp)
        tmp += w
        tmp *= dt
        phi += tmp
        np.multiply(u, dt, out=tmp)
        w += tmp
        np.abs(phi, out=tmp)
        np.greater_equal(tmp, tol_a, out=bad)
        np.abs(w, out=tmp)
        np.greater_equal(tmp, tol_r, out=bad2)
        bad |= bad2
        np.copyto(last_bad, i + 1, where=bad)
    t_settle = np.asarray((last_bad + 1) * dt, dtype=float)
    return np.where(t_settle > settings.horizon_s - settings.hold_s, np.inf, t_settle)


@dataclass(frozen=True)
class SettleMap:
    """Settle time ``time_s[i, j]`` at ``k_w[i]``, ``k_q[j]`` for one turn (seed Fig. 10)."""

    phi0_deg: float
    k_w: FloatArray
    k_q: FloatArray
    time_s: FloatArray
    settings: StudySettings


def settle_time_map(phi0_deg: float, settings: StudySettings) -> SettleMap:
    """Settle times over the (k_w, k_q) grid, simulated as one batch."""
    grid = settings.grid()
    t = settle_times(settings.turn_rad(phi0_deg), grid[None, :], grid[:, None], settings)
    return SettleMap(float(phi0_deg), grid, grid, t, settings)


def efficient_curve(smap: SettleMap) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Efficient-coefficient curve: ``k_q`` of minimum settle time for each ``k_w`` (Fig. 11).

    Rows without a finite minimum, or whose minimum lies on the grid edge (the
    true minimum may be outside), are dropped. Returns ``(k_w, k_q, time_s)``.
    """
    j = np.argmin(smap.time_s, axis=1)
    tmin = smap.time_s[np.arange(smap.k_w.size), j]
    ok = np.isfinite(tmin) & (j > 0) & (j < smap.k_q.size - 1)
    return smap.k_w[ok], smap.k_q[j[ok]], tmin[ok]


def fit_parabola(
    k_w: ArrayLike, k_q: ArrayLike, loss: str = "soft_l1", scale: float = 0.025
) -> float:
    """``f0`` of ``k_q = f0 k_w^2`` (eq. (27)) by least squares (robust loss by default)."""
    x = np.asarray(k_w, dtype=float) ** 2
    y = np.asarray(k_q, dtype=float)
    if x.size == 0:
        return np.nan
    f_ls = float(x @ y / (x @ x))
    if loss == "linear":
        return f_ls
    from scipy.optimize import least_squares  # here: the gain study's options stay light

    return float(least_squares(lambda f: f[0] * x - y, [f_ls], loss=loss, f_scale=scale).x[0])


def f0_for_angle(phi0_deg: float, settings: StudySettings) -> float:
    """``f0(phi0)``: the parabola (27) fitted to the efficient-coefficient curve."""
    kw, kq, _ = efficient_curve(settle_time_map(phi0_deg, settings))
    return fit_parabola(kw, kq, settings.fit_loss, settings.grid_step)


def f0_model(phi0_rad: ArrayLike, c1: float, p1: float, c2: float, p2: float) -> FloatArray:
    """Seed eq. (28): ``f0 = c1/phi0^p1 + c2/phi0^p2`` (``phi0`` in radians)."""
    phi = np.asarray(phi0_rad, dtype=float)
    return c1 / phi**p1 + c2 / phi**p2


def fit_f0_curve(
    phi0_deg: ArrayLike, f0: ArrayLike, quaternion_term: str = "twice"
) -> dict[str, float]:
    """Fit eq. (28) (``phi0`` in radians, as the seed's numbers imply) to ``f0(phi0)``.

    Started from the seed's coefficients scaled to the convention
    (eq. (28) is written for ``"vector"``; ``"twice"`` halves ``c1``, ``c2``).
    """
    phi = np.radians(np.asarray(phi0_deg, dtype=float))
    y = np.asarray(f0, dtype=float)
    ok = np.isfinite(y)
    if ok.sum() < 4:
        raise ValueError("need f0 at 4 or more angles to fit eq. (28)")
    from scipy.optimize import curve_fit  # here: the gain study's options stay light

    s = 1.0 / term_scale(quaternion_term)
    p0 = [
        SEED_FIT_EQ28["c1"] * s,
        SEED_FIT_EQ28["p1"],
        SEED_FIT_EQ28["c2"] * s,
        SEED_FIT_EQ28["p2"],
    ]
    popt, _ = curve_fit(f0_model, phi[ok], y[ok], p0=p0, maxfev=20000)
    return dict(zip(("c1", "p1", "c2", "p2"), (float(v) for v in popt), strict=True))


def rule_settle_times(
    phi0_deg: ArrayLike, k_w: float, k_q: ArrayLike, settings: StudySettings
) -> FloatArray:
    """Settle times along angles for given gains (one batch; seed Fig. 15)."""
    return settle_times(settings.turn_rad(phi0_deg), k_q, k_w, settings)
