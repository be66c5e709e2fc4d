"""Set-membership attitude estimator: a box on the multiplicative error state (docs/models.md §2.5).

The belief of each run is a reference attitude ``q_ref`` and a box

    e in [c_e - r_e, c_e + r_e],   w in [c_w - r_w, c_w + r_w]

where ``e = log(q_ref^-1 q)`` is the body-frame rotation vector from the reference to
the true attitude and ``w`` the body rate. The guarantee: if the true state is in the
box and the disturbance and measurement errors are admissible (``|d_i| <= D_i``,
``|n_i| <= b_a``, ``|m_i| <= b_w``, :mod:`estim.attitude.model`), it is in the box after
``predict``, ``update`` and the re-centring. All enclosures are computed in
midpoint-radius interval arithmetic (``x in (c, r)`` means ``|x - c| <= r`` per
component), which over-approximates but never loses a point:

* products: ``(c1, r1)(c2, r2) in (c1 c2, |c1| r2 + r1 |c2| + r1 r2)``;
* linear maps: ``M (c, r) in (M c, |M| r)``.

**Rate** over a step ``dt`` (torque ``M_u`` held, ``h`` in its interval ``H``): with
``F(W) = J_b^-1 (M_u + [-D, D] - W x (J_g W + H))``, an a-priori enclosure ``W*`` of
``w(s)`` on ``[0, dt]`` is verified by ``W0 + [0, dt] F(W*) subset W*`` (Picard
inclusion, iterated with inflation), then ``w(dt) in W0 + dt F(W*)`` (mean-value form).

**Attitude**: ``q(dt) = q(0) exp(phi)`` with (Magnus) ``phi = int w ds + rho``,
``int w in dt W0 + dt^2/2 F(W*)`` (Taylor model) and ``|rho| <= |W*| |F(W*)| dt^3/6``
(the second Magnus term ``1/2 int int w(s1) x w(s2)`` with ``w(s2) - w(s1) in (s2 - s1)
F(W*)``, doubled for the higher terms). The reference moves by the centre ``c`` of that
enclosure, ``q_ref' = q_ref exp(c)``; ``exp(-c) exp(e) exp(phi) = exp(R(c)^T e)
exp(delta')`` (conjugation rotates the rotation vector exactly) with ``delta' =
log(exp(-c) exp(c + delta)) = J_r(c) delta + O(|delta|^2)``, ``||J_r|| <= 1``, so
``|delta'_i| <= |delta| + |delta|^2``; the product is enclosed with the
Baker-Campbell-Hausdorff formula of so(3): ``log(exp(a) exp(b)) = a + b + 1/2 a x b + R3``,
``|R3| <= K |a| |b| (|a| + |b|)``; the third-order terms have coefficient 1/12 and
the tail is smaller still for ``|a| + |b| <= 1/2``, so ``K = 1/4`` is taken there (a
margin of 3 on the leading term; not proved for the whole tail, tested with hypothesis).
Beyond that radius, or when the Picard inclusion does not close, the step is halved;
after 6 halvings the predicted set is the whole space (status ``n_unbounded``, still
guaranteed) and the next update restarts from the measurement.

**Measurement** ``q_m = q exp(n)``: ``e = log(exp(z) exp(-n))`` with ``z =
log(q_ref^-1 q_m)``, enclosed by the same BCH form; ``w in w_m - [-b_w, b_w]``. The
predicted box is intersected with both. An empty intersection (the data contradict
the model: inadmissible noise) is a reported status: the run's counter ``n_empty``
grows and the box restarts from the measurement.

**Re-centring** after each update: ``q_ref' = q_ref exp(c_e)``, ``e' = log(exp(-c_e)
exp(e))`` (BCH again), so the box stays centred on the estimate. Floating-point
rounding is covered by a relative inflation of 1e-12 and an absolute one
(``abs_inflation_rad`` per step, default 1e-12 rad and rad/s), which also covers
the error of the fixed-step RK4 truth simulators.

Batched over a leading axis of ``R`` runs; beliefs are immutable values.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.box.options import DEFAULTS
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeBelief,
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    check_runs,
    check_step,
    rate_component,
    run_states,
)
from kalman_vs_infoset.estim.base import Estimator, Extremes, StateFunction, Status
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly
from kalman_vs_infoset.numerics.rotations import cross, qexp, qinv, qlog, qmatrix, qmul

FloatArray = NDArray[np.float64]
BCH_K = 0.25
BCH_MAX = 0.5
REL_INFLATION = 1e-12
#: the containment check's allowance (rad, rad/s): its own rounding (the error of the
#: truth through quaternion products and the log, a few ulps of components up to about
#: pi) and nothing more; the sets' inflation covers their rounding. (It allowed 1e-12,
#: 0.3 % of the narrowest rate set seen; every published count is the same at zero.)
INSIDE_TOL = 8 * float(np.finfo(float).eps)
_J, _K = [1, 2, 0], [2, 0, 1]


class NoEnclosure(Exception):
    """An enclosure of a step could not be closed (the Picard inclusion within its
    iterations, or a remainder of the sets' maps): the step is too long."""


# --- midpoint-radius interval arithmetic (arrays of centres c and radii r) -------------
def imul(c1, r1, c2, r2):
    return c1 * c2, np.abs(c1) * r2 + r1 * np.abs(c2) + r1 * r2


def icross(c1, r1, c2, r2):
    """Enclosure of ``a x b`` for ``a in (c1, r1)``, ``b in (c2, r2)`` (per component:
    ``a_j b_k - a_k b_j`` with the product rule above)."""
    a = np.stack([c1, r1, np.abs(c1), c2, r2, np.abs(c2)])
    c1j, r1j, a1j, c2j, r2j, a2j = a[..., _J]
    c1k, r1k, a1k, c2k, r2k, a2k = a[..., _K]
    rad = (a1j + r1j) * (a2k + r2k) - a1j * a2k + (a1k + r1k) * (a2j + r2j) - a1k * a2j
    return c1j * c2k - c1k * c2j, rad


def imat(m: FloatArray, c, r):
    return c @ m.T, r @ np.abs(m).T


def inorm_max(c, r):
    """Upper bound of ``|x|`` over the box."""
    m = np.abs(c) + r
    return np.sqrt(np.add.reduce(m * m, axis=-1))


def _norm(x: FloatArray) -> FloatArray:
    return np.sqrt(np.add.reduce(x * x, axis=-1))


def bch(ca, ra, cb, rb):
    """Enclosure of ``log(exp(a) exp(b))`` for ``a in (ca, ra)``, ``b in (cb, rb)``.

    ``a + b + 1/2 a x b + R3``; ``a x b - ca x cb = (a - ca) x b + ca x (b - cb)`` is bounded
    per component by ``|ra| |b|max + |ca| |rb|`` (norms), ``|R3| <= K |a| |b| (|a| + |b|)``.
    """
    na, nb = inorm_max(ca, ra), inorm_max(cb, rb)
    if np.any(na + nb > BCH_MAX):
        raise FloatingPointError(
            f"attitude box too large for the BCH enclosure (|a| + |b| = {np.max(na + nb):.3g})"
        )
    return _bch_terms(ca, ra, cb, rb, na, nb)


def _bch_terms(ca, ra, cb, rb, na, nb):
    xr = _norm(ra) * nb + _norm(ca) * _norm(rb)
    rem = BCH_K * na * nb * (na + nb)
    return ca + cb + 0.5 * cross(ca, cb), ra + rb + (0.5 * xr + rem)[..., None]


def bch_or_ball(ca, ra, cb, rb):
    """:func:`bch` for the runs within its radius; for the others the ball
    ``|log(exp(a) exp(b))| <= min(|a| + |b|, pi)`` (the angle of a product of two
    rotations is at most the sum of their angles, and a principal rotation vector is at
    most pi long), as a box about zero. Coarse, but sound at any size: the measurement
    and the re-centring use it, so a large measurement error bound gives a large box
    instead of an error."""
    na, nb = inorm_max(ca, ra), inorm_max(cb, rb)
    ok = na + nb <= BCH_MAX
    if np.all(ok):
        return _bch_terms(ca, ra, cb, rb, na, nb)
    c, r = _bch_terms(ca, ra, cb, rb, np.where(ok, na, 0.0), np.where(ok, nb, 0.0))
    ball = np.broadcast_to(np.minimum(na + nb, np.pi)[..., None], r.shape)
    return np.where(ok[..., None], c, 0.0), np.where(ok[..., None], r, ball)


def _inflate(c, r, abs_r: float):
    return r + REL_INFLATION * (np.abs(c) + r) + abs_r


def _rotmat(rotvec: FloatArray) -> FloatArray:
    return qmatrix(qexp(rotvec))


def _with(belief: BoxAttitudeBelief, **changes: Any) -> BoxAttitudeBelief:
    """A copy of ``belief`` with ``changes`` (arrays frozen), skipping re-validation."""
    new = object.__new__(BoxAttitudeBelief)
    for name in BoxAttitudeBelief.__dataclass_fields__:
        value = changes.get(name, getattr(belief, name))
        if isinstance(value, np.ndarray) and value.flags.writeable:
            value = readonly(value, copy=False)
        object.__setattr__(new, name, value)
    return new


#: the per-run fields of a box belief (rows of a batch)
_PER_RUN = ("q_ref", "e_c", "e_r", "w_c", "w_r", "n_empty", "last_empty", "n_unbounded")


def _runs_of(belief: BoxAttitudeBelief, idx) -> BoxAttitudeBelief:
    """The runs ``idx`` of a batched belief, as a batch of their own."""
    return _with(belief, **{name: getattr(belief, name)[idx] for name in _PER_RUN})


def _control_of(ctrl: AttitudeControl, idx) -> AttitudeControl:
    """The runs ``idx`` of batched inputs (a single row is shared by every run)."""
    rows = (ctrl.torque_Nm, ctrl.h_lo_Nms, ctrl.h_hi_Nms)
    return AttitudeControl(*(a if a.shape[0] == 1 else a[idx] for a in rows))


def _joined(belief: BoxAttitudeBelief, parts) -> BoxAttitudeBelief:
    """``belief`` with the runs of each ``(idx, sub)`` of ``parts`` replaced by ``sub``'s."""
    out = {name: np.array(getattr(belief, name)) for name in _PER_RUN}
    for idx, sub in parts:
        for name in _PER_RUN:
            out[name][idx] = getattr(sub, name)
    return _with(belief, **out)


class EmptyRunCounts:
    """The status of a batched attitude set from its per-run counters ``n_empty`` (updates
    whose intersection was empty) and ``last_empty`` (the last update was): shared by the
    box and the sets intersected with it."""

    n_empty: FloatArray
    last_empty: FloatArray

    @property
    def is_empty(self) -> bool:
        """Never: an update whose intersection is empty restarts the run's set from the
        measurement's box, which holds states (``status`` reports the contradiction, as
        the intercept sets' kept set does)."""
        return False

    @property
    def status(self) -> Status:
        """``CONTRADICTION`` when some run's last update was empty, else ``OK``."""
        return Status.CONTRADICTION if bool(np.any(self.last_empty)) else Status.OK

    @property
    def contradictions(self) -> int:
        return int(np.sum(self.n_empty))

    @property
    def empty_counts(self) -> NDArray[np.int_]:
        return np.asarray(self.n_empty, dtype=int)


@dataclass(frozen=True, eq=False)
class BoxAttitudeBelief(EmptyRunCounts, AttitudeBelief):
    """Reference quaternions ``(R, 4)`` and boxes (centre, radius) of ``e`` and ``w`` ``(R, 3)``.

    ``n_empty`` counts, per run, the updates whose intersection was empty; ``last_empty`` flags
    the runs whose last update was; ``n_unbounded`` counts, per run, the predictions
    whose enclosure could not be closed (a step far too long for the rates, or a box
    too large for the BCH enclosure): the set then is the whole space until the next
    measurement (still guaranteed; the results report it as ``unbounded_steps``). A
    batch that does not close is predicted run by run, so only the runs that cannot be
    enclosed go to the whole space and count the step.
    """

    q_ref: FloatArray
    e_c: FloatArray
    e_r: FloatArray
    w_c: FloatArray
    w_r: FloatArray
    n_empty: FloatArray = field(default=None)  # type: ignore[arg-type]  # None: filled in __post_init__
    last_empty: FloatArray = field(default=None)  # type: ignore[arg-type]  # None: filled in __post_init__
    n_unbounded: NDArray[np.int_] = field(default=None)  # type: ignore[arg-type]  # None: zeros

    def __post_init__(self) -> None:
        for name in ("q_ref", "e_c", "e_r", "w_c", "w_r"):
            object.__setattr__(self, name, readonly(np.atleast_2d(getattr(self, name))))
        runs = self.q_ref.shape[0]
        if self.n_empty is None:
            object.__setattr__(self, "n_empty", readonly(np.zeros(runs, dtype=int)))
        if self.last_empty is None:
            object.__setattr__(self, "last_empty", readonly(np.zeros(runs, dtype=bool)))
        if self.n_unbounded is None:
            object.__setattr__(self, "n_unbounded", readonly(np.zeros(runs), dtype=int))

    @property
    def runs(self) -> int:
        return self.q_ref.shape[0]

    @property
    def unbounded_counts(self) -> NDArray[np.int_]:
        return np.asarray(self.n_unbounded, dtype=int)

    def centre(self) -> FloatArray:
        """``(q, w)`` of the box centre, ``(R, 7)``."""
        q = qmul(self.q_ref, qexp(self.e_c))
        return np.concatenate([q, self.w_c], axis=-1)

    def error_of(self, state: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``(e, w)`` of true states ``(R, >=7)`` in this belief's coordinates."""
        x = np.atleast_2d(np.asarray(state, dtype=float))
        return qlog(qmul(qinv(self.q_ref), x[:, 0:4])), x[:, 4:7]

    def inside(self, state: ArrayLike, tol: float = INSIDE_TOL) -> NDArray[np.bool_]:
        """Per run: whether the state ``(q, w, ...)`` lies in the box."""
        e, w = self.error_of(run_states(state, self.runs))
        ok_e = np.all(np.abs(e - self.e_c) <= self.e_r + tol, axis=-1)
        ok_w = np.all(np.abs(w - self.w_c) <= self.w_r + tol, axis=-1)
        return ok_e & ok_w

    def contains(self, state: ArrayLike) -> bool:
        return bool(np.all(self.inside(state)))

    def attitude_bound_rad(self) -> FloatArray:
        """Guaranteed bound of the angle between the true and the centre attitude, per run.

        ``log(exp(-c) exp(e)) = e - c + O(|c||e|)``: ``|e - c| + |c| |e| (1 + ...)``.
        """
        ne = inorm_max(self.e_c, self.e_r)
        nc = np.linalg.norm(self.e_c, axis=-1)
        with np.errstate(invalid="ignore"):  # 0 * inf of a run that is the whole space
            bound = np.linalg.norm(self.e_r, axis=-1) + nc * ne
        return np.where(np.all(np.isfinite(self.e_r), axis=-1), bound, np.inf)

    def vertices(self) -> FloatArray:
        """The 64 vertices of the box of run 0 as states ``(64, 7)``."""
        signs = np.array(list(product((-1.0, 1.0), repeat=6)))
        e = self.e_c[0] + signs[:, 0:3] * self.e_r[0]
        w = self.w_c[0] + signs[:, 3:6] * self.w_r[0]
        q = qmul(np.broadcast_to(self.q_ref[0], (64, 4)), qexp(e))
        return np.concatenate([q, w], axis=-1)

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of a :class:`RateComponent` over run 0's box, at its vertices
        (exact: the rate is a coordinate of the box); any other function is refused
        with ``TypeError``."""
        fn = rate_component(fn, "the attitude box")
        pts = self.vertices()
        vals = np.asarray(fn(pts), dtype=float)
        i, j = int(np.argmin(vals)), int(np.argmax(vals))
        return Extremes(float(vals[i]), pts[i], float(vals[j]), pts[j])


@dataclass(frozen=True)
class BoxAttitudeEstimator(Estimator[BoxAttitudeBelief, AttitudePrior]):
    """Guaranteed box estimator of attitude and rate (see the module docstring)."""

    model: AttitudeModel
    abs_inflation_rad: float = DEFAULTS.abs_inflation_rad
    picard_iterations: int = 8

    def __post_init__(self) -> None:
        if not self.abs_inflation_rad >= 0:
            raise ValueError("abs_inflation_rad must be >= 0")

    # -- measurement enclosure ---------------------------------------------------------
    def measurement_box(self, q_ref: FloatArray, meas: AttitudeMeasurement):
        """``(e_c, e_r, w_c, w_r)`` of all states compatible with ``meas`` alone."""
        z = qlog(qmul(qinv(q_ref), meas.quat))
        n_r = np.broadcast_to(self.model.meas_angle_bound_rad, z.shape)
        e_c, e_r = bch_or_ball(z, np.zeros_like(z), np.zeros_like(z), n_r)
        w_r = np.broadcast_to(self.model.meas_rate_bound_radps, z.shape)
        return e_c, _inflate(e_c, e_r, 0.0), meas.rate_radps, w_r.copy()

    def initial(self, prior: AttitudePrior) -> BoxAttitudeBelief:
        """The box of the first measurement (reference = the measured attitude)."""
        meas = prior.measurement
        e_c, e_r, w_c, w_r = self.measurement_box(meas.quat, meas)
        return self._recentre(BoxAttitudeBelief(meas.quat, e_c, e_r, w_c, w_r))

    # -- Estimator interface -----------------------------------------------------------
    def _rate_field(self, wc, wr, ctrl: AttitudeControl):
        """Enclosure of ``J_b^-1 (M_u + d - w x (J_g w + h))`` over ``w in (wc, wr)``, ``h``, ``d``
        (interval cross product per component)."""
        m = self.model
        hc = 0.5 * (ctrl.h_lo_Nms + ctrl.h_hi_Nms)
        hr = 0.5 * (ctrl.h_hi_Nms - ctrl.h_lo_Nms)
        jc, jr = imat(m.inertia_kgm2, wc, wr)
        gc, gr = icross(wc, wr, jc + hc, jr + hr)
        return imat(m.j_b_inv, ctrl.torque_Nm - gc, gr + m.disturbance_bound_Nm)

    def predict(
        self, belief: BoxAttitudeBelief, dt_s: float, control: AttitudeControl | None = None
    ) -> BoxAttitudeBelief:
        """Enclosure after ``dt_s`` under the known inputs ``control`` held over the step
        (:class:`AttitudeControl`; None: no torque, no momentum); a step too long for the
        a-priori enclosure is halved (the inputs hold over the whole step, so each half is
        enclosed as well)."""
        check_step(dt_s)
        if control is None:
            control = AttitudeControl.zero(belief.runs)
        elif not isinstance(control, AttitudeControl):
            raise TypeError("control must be an AttitudeControl")
        check_runs(belief.runs, control.runs, "control")
        return self._predict(belief, dt_s, control, depth=0)

    def _predict(
        self, belief: BoxAttitudeBelief, dt_s: float, ctrl: AttitudeControl, depth: int
    ) -> BoxAttitudeBelief:
        lost = ~np.all(np.isfinite(belief.e_r), axis=-1)
        if lost.all():
            return belief  # already "any state": stays so until the next measurement
        if lost.any():  # the others are predicted; a lost run stays the whole space
            keep = np.flatnonzero(~lost)
            sub = self._predict(_runs_of(belief, keep), dt_s, _control_of(ctrl, keep), depth)
            return _joined(belief, [(keep, sub)])
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                return self._predict_once(belief, dt_s, ctrl)
        except (NoEnclosure, FloatingPointError):
            if belief.runs > 1:
                # each run on its own: a run's set must not depend on the runs batched
                # with it (one run too fast to enclose would halve, or lose, them all)
                parts = [
                    (np.array([i]), self._predict(_runs_of(belief, [i]), dt_s,
                                                  _control_of(ctrl, [i]), depth))
                    for i in range(belief.runs)
                ]  # fmt: skip
                return _joined(belief, parts)
            if depth >= 6:
                # no enclosure: the guaranteed set is the whole state space (the next
                # update restarts from the measurement); counted in n_unbounded
                inf = np.full_like(belief.e_r, np.inf)
                return _with(
                    belief, e_c=np.zeros_like(inf), e_r=inf, w_r=inf.copy(),
                    n_unbounded=belief.n_unbounded + 1,
                )  # fmt: skip
            half = self._predict(belief, 0.5 * dt_s, ctrl, depth + 1)
            return self._predict(half, 0.5 * dt_s, ctrl, depth + 1)

    def rate_enclosure(self, wc, wr, ctrl: AttitudeControl, dt_s: float):
        """``(W*, F(W*))`` as centre/radius pairs: an a-priori enclosure ``W*`` of the rate
        ``w(s)``, ``s`` in ``[0, dt]``, from ``W0 = (wc, wr)`` (Picard inclusion:
        ``W0 + [0, dt] F(W*)`` inside ``W*``, verified), and the rate field over it;
        :class:`NoEnclosure` when it does not close within ``picard_iterations``."""
        fc, fr = self._rate_field(wc, wr, ctrl)
        sc, sr = imul(0.5 * dt_s, 0.5 * dt_s, fc, fr)
        ac, ar = wc + sc, 2.0 * (wr + sr) + 1e-15
        for _ in range(self.picard_iterations):
            fc, fr = self._rate_field(ac, ar, ctrl)
            sc, sr = imul(0.5 * dt_s, 0.5 * dt_s, fc, fr)
            tc, tr = wc + sc, wr + sr
            if not np.all(np.isfinite(tr)):
                raise NoEnclosure
            if np.all(np.abs(tc - ac) + tr <= ar):
                return (ac, ar), self._rate_field(ac, ar, ctrl)
            lo, hi = np.minimum(ac - ar, tc - tr), np.maximum(ac + ar, tc + tr)
            ac, ar = 0.5 * (lo + hi), 0.5 * (hi - lo) * 1.5 + 1e-15
        raise NoEnclosure

    def _predict_once(
        self, belief: BoxAttitudeBelief, dt_s: float, ctrl: AttitudeControl
    ) -> BoxAttitudeBelief:
        w0c, w0r = belief.w_c, belief.w_r
        (ac, ar), (fc, fr) = self.rate_enclosure(w0c, w0r, ctrl, dt_s)
        w1c = w0c + dt_s * fc
        w1r = _inflate(w1c, w0r + dt_s * fr, self.abs_inflation_rad)
        # attitude (Taylor model): int_0^dt w = dt w(0) + int_0^dt s F ds in dt W0 + dt^2/2 F(W*);
        # Magnus remainder 1/2 int int w(s1) x w(s2): w(s2) - w(s1) in (s2 - s1) F(W*), so
        # |rho| <= 1/2 |W*| |F(W*)| dt^3/6, doubled for the higher terms.
        # phi = c + delta with c the centre; exp(-c) exp(e) exp(phi) = exp(R(c)^T e) exp(delta'),
        # delta' = log(exp(-c) exp(c + delta)) = J_r(c) delta + O(|delta|^2), ||J_r|| <= 1:
        # |delta'_i| <= |delta| + |delta|^2.
        wmax = inorm_max(ac, ar)
        fmax = inorm_max(fc, fr)
        c = dt_s * w0c + 0.5 * dt_s**2 * fc
        dn = np.linalg.norm(dt_s * w0r + 0.5 * dt_s**2 * fr, axis=-1) + wmax * fmax * dt_s**3 / 6
        dr = np.broadcast_to((dn + dn * dn)[..., None], ac.shape)
        rot_t = np.swapaxes(_rotmat(c), -1, -2)
        rc = np.einsum("...ij,...j->...i", rot_t, belief.e_c)
        rr = np.einsum("...ij,...j->...i", np.abs(rot_t), belief.e_r)
        ec, er = bch(rc, rr, np.zeros_like(rc), dr)
        er = _inflate(ec, er, self.abs_inflation_rad)
        q_ref = qmul(belief.q_ref, qexp(c))
        return _with(belief, q_ref=q_ref, e_c=ec, e_r=er, w_c=w1c, w_r=w1r)

    def meet(self, belief: BoxAttitudeBelief, measurement: AttitudeMeasurement):
        """``(q_ref, lo, hi, empty)``: the box met with the measurement's box, before the
        re-centring, as ``[e, w]`` bounds (6 a run) about ``q_ref``. A lost run (its box
        the whole space) and a run whose intersection is empty (the data contradict the
        model) restart from the measurement's box about the measured attitude itself:
        about the old reference, a measurement far from it is enclosed by BCH terms
        that grow with the distance (a contradiction 90 deg away restarted at 2.7 rad a
        side, and the next prediction was the whole space). The set estimators meet the
        box the same way (:func:`..sets.maps.meet_measurement`)."""
        lost = ~np.all(np.isfinite(belief.e_r), axis=-1)
        q_ref = np.where(lost[:, None], measurement.quat, belief.q_ref)
        e_c = np.where(lost[:, None], 0.0, belief.e_c)
        mec, mer, mwc, mwr = self.measurement_box(q_ref, measurement)
        own = np.concatenate([e_c - belief.e_r, belief.w_c - belief.w_r], -1)
        lo = np.maximum(own, np.concatenate([mec - mer, mwc - mwr], -1))
        own = np.concatenate([e_c + belief.e_r, belief.w_c + belief.w_r], -1)
        hi = np.minimum(own, np.concatenate([mec + mer, mwc + mwr], -1))
        empty = np.any(lo > hi, axis=-1)
        if np.any(empty):  # restart about the measured attitude (the lost runs already are)
            q_ref = np.where(empty[:, None], measurement.quat, q_ref)
            mec, mer, mwc, mwr = self.measurement_box(q_ref, measurement)
            lo = np.where(empty[:, None], np.concatenate([mec - mer, mwc - mwr], -1), lo)
            hi = np.where(empty[:, None], np.concatenate([mec + mer, mwc + mwr], -1), hi)
        return q_ref, lo, hi, empty

    def update(self, belief: BoxAttitudeBelief, measurement: Any) -> BoxAttitudeBelief:
        """Intersect with the measurement's box; empty -> restart from it (status counted)."""
        if not isinstance(measurement, AttitudeMeasurement):
            raise TypeError("measurement must be an AttitudeMeasurement")
        check_runs(belief.runs, measurement.runs, "measurement")
        q_ref, lo, hi, empty = self.meet(belief, measurement)
        new = _with(
            belief,
            q_ref=q_ref,
            e_c=0.5 * (lo[:, :3] + hi[:, :3]),
            e_r=0.5 * (hi[:, :3] - lo[:, :3]),
            w_c=0.5 * (lo[:, 3:] + hi[:, 3:]),
            w_r=0.5 * (hi[:, 3:] - lo[:, 3:]),
            n_empty=belief.n_empty + empty,
            last_empty=empty,
        )
        return self._recentre(new)

    def _recentre(self, belief: BoxAttitudeBelief) -> BoxAttitudeBelief:
        c = belief.e_c
        ec, er = bch_or_ball(-c, np.zeros_like(c), c, belief.e_r)
        er = _inflate(ec, er, 0.0)
        q_ref = qmul(belief.q_ref, qexp(c))
        return _with(belief, q_ref=q_ref, e_c=ec, e_r=er)
