"""Shared machinery of the attitude zonotope and ellipsoid (docs/models.md §2.5).

A belief of :mod:`estim.attitude.sets.zonotope` or :mod:`estim.attitude.sets.ellipsoid` is the
intersection ``S = Z ∩ B`` of a correlated set ``Z`` (zonotope or ellipsoid) and the
box ``B`` of :class:`estim.attitude.box.estimator.BoxAttitudeEstimator`, both on the error state

.. math:: x = (e, w) \\in R^6, \\qquad e = \\log(q_{ref}^{-1} q),

in the same coordinates: ``q_ref`` is the box's reference. ``B`` is the box estimator
run unchanged (the same values as a box run alone on the same data), so ``S``, whose
interval hull is :math:`\\mathrm{hull}(Z) \\cap B`, is never larger than the box per
axis; ``Z`` keeps what the box drops, the correlation of ``e`` and ``w`` (the attitude
grows by about ``dt w``).

**Prediction**: with :math:`x' \\in A x + b \\oplus [-\\rho, \\rho]` over the hull of ``S``
(:func:`kalman_vs_infoset.estim.attitude.sets.maps.predict_map`), :math:`Z' \\supset A Z + b \\oplus
[-\\rho, \\rho]` (the subclass's outer bound) contains the image of ``S`` (the remainder
holds for the states of ``S``, all in the hull), and so does ``S' = Z' ∩ B'`` with
``B'`` the box's prediction.

**Update**: the box's intersection with the measurement box, ``[lo, hi]`` (before the
box re-centres), is applied to ``Z`` as six axis strips :math:`lo_i \\le x_i \\le hi_i`
(the subclass's outer strip update); ``B`` is updated by the box estimator. Then both
re-centre at the box's new centre (:func:`estim.attitude.sets.maps.recentre_map` for
``Z``).

An update whose intersection is empty (the box's, or the strips' on ``Z``: the data
contradict the model) is counted in ``n_empty`` and ``Z`` restarts from the box's set
(the measurement box when the box was empty, as the box itself does). A prediction whose
remainders cannot be enclosed (Picard inclusion not closing, BCH radius exceeded) makes
``Z`` the box ``B'`` (still guaranteed).
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass, field
from itertools import product
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.box.estimator import (
    INSIDE_TOL,
    BoxAttitudeBelief,
    BoxAttitudeEstimator,
    EmptyRunCounts,
    inorm_max,
)
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeBelief,
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    check_runs,
    rate_component,
    run_states,
)
from kalman_vs_infoset.estim.attitude.sets.maps import (
    NoEnclosure,
    meet_measurement,
    predict_map,
    recentre_map,
)
from kalman_vs_infoset.estim.base import Estimator, Extremes, StateFunction
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly
from kalman_vs_infoset.numerics.rotations import qexp, qinv, qlog, qmul

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SetAttitudeBelief(EmptyRunCounts, AttitudeBelief):
    """``S = Z ∩ B``: the box belief ``box`` and a set ``Z`` of centre ``z_c`` ``(R, 6)`` and
    matrix ``z_m`` (generators or shape matrix, by subclass). Runs whose box is not finite
    (no enclosure, :class:`BoxAttitudeBelief`) are the whole space until the next update."""

    box: BoxAttitudeBelief
    z_c: FloatArray
    z_m: FloatArray
    n_empty: FloatArray = field(default=None)  # type: ignore[arg-type]  # None: filled in __post_init__
    last_empty: FloatArray = field(default=None)  # type: ignore[arg-type]  # None: filled in __post_init__

    def __post_init__(self) -> None:
        for name in ("z_c", "z_m"):
            object.__setattr__(
                self, name, readonly(np.array(getattr(self, name), float), copy=False)
            )
        # the counts too (given ones were writable and shared with the belief before)
        n_empty = np.zeros(self.runs, int) if self.n_empty is None else self.n_empty
        last = np.zeros(self.runs, bool) if self.last_empty is None else self.last_empty
        object.__setattr__(self, "n_empty", readonly(n_empty, int, copy=None))
        object.__setattr__(self, "last_empty", readonly(last, bool, copy=None))

    @abstractmethod
    def set_radius(self) -> FloatArray:
        """Per-axis radius of the interval hull of ``Z`` about ``z_c``, ``(R, 6)``."""

    @abstractmethod
    def set_inside(self, d: FloatArray, tol: float) -> NDArray[np.bool_]:
        """Per run: whether ``z_c + d`` lies in ``Z`` (``d`` of shape ``(R, 6)``)."""

    @property
    def runs(self) -> int:
        return self.box.runs

    @property
    def q_ref(self) -> FloatArray:
        return self.box.q_ref

    @property
    def lost(self) -> NDArray[np.bool_]:
        return ~(np.all(np.isfinite(self.box.e_r), -1) & np.all(np.isfinite(self.box.w_r), -1))

    def box_hull(self) -> tuple[FloatArray, FloatArray]:
        """Centre and radius ``(R, 6)`` of the box ``B``."""
        return box_cr(self.box)

    def hull(self) -> tuple[FloatArray, FloatArray]:
        """Centre and radius of the hull of ``S``: ``hull(Z) ∩ B`` (``B`` for lost runs)."""
        bc, br = self.box_hull()
        zr = self.set_radius()
        with np.errstate(invalid="ignore"):
            lo = np.maximum(bc - br, self.z_c - zr)
            hi = np.minimum(bc + br, self.z_c + zr)
        lost = self.lost[:, None] | ~(lo <= hi)
        lo, hi = np.where(lost, bc - br, lo), np.where(lost, bc + br, hi)
        with np.errstate(invalid="ignore"):  # -inf + inf of a run that is the whole space
            hc, hr = 0.5 * (lo + hi), 0.5 * (hi - lo)
        whole = ~np.isfinite(br)  # the box's centre and its infinite radius
        return np.where(whole, bc, hc), np.where(whole, br, hr)

    @property
    def n_unbounded(self) -> NDArray[np.int_]:
        """Per run: the box's predictions that were the whole space (its
        ``n_unbounded``)."""
        return self.box.n_unbounded

    @property
    def unbounded_counts(self) -> NDArray[np.int_]:
        return self.box.unbounded_counts

    def centre(self) -> FloatArray:
        """``(q, w)`` of the centre of the hull of ``S``, ``(R, 7)``."""
        hc, _ = self.hull()
        return np.concatenate([qmul(self.q_ref, qexp(hc[:, :3])), hc[:, 3:]], axis=-1)

    def error_of(self, state: ArrayLike) -> FloatArray:
        """``(e, w)`` ``(R, 6)`` of true states ``(R, >=7)`` in this belief's coordinates."""
        x = np.atleast_2d(np.asarray(state, dtype=float))
        return np.concatenate([qlog(qmul(qinv(self.q_ref), x[:, 0:4])), x[:, 4:7]], -1)

    def inside(self, state: ArrayLike, tol: float = INSIDE_TOL) -> NDArray[np.bool_]:
        """Per run: whether the state ``(q, w, ...)`` lies in ``Z ∩ B`` (exact tests)."""
        state = run_states(state, self.runs)
        x = self.error_of(state)
        ok_box = self.box.inside(state, tol)
        lost = self.lost
        d = np.where(lost[:, None], 0.0, x - self.z_c)
        return ok_box & (lost | self.set_inside(d, tol))

    def contains(self, state: ArrayLike) -> bool:
        return bool(np.all(self.inside(state)))

    def attitude_bound_rad(self) -> FloatArray:
        """Bound of the angle between the true and the centre attitude (the box's formula on
        the hull: :math:`|r_e| + |h_e| \\max|e|`)."""
        hc, hr = self.hull()
        ne = inorm_max(hc[:, :3], hr[:, :3])
        with np.errstate(invalid="ignore"):  # 0 * inf of a run that is the whole space
            bound = np.linalg.norm(hr[:, :3], axis=-1) + np.linalg.norm(hc[:, :3], axis=-1) * ne
        return np.where(np.all(np.isfinite(hr[:, :3]), axis=-1), bound, np.inf)

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of a :class:`RateComponent` over the 64 vertices of run 0's hull
        (an outer range over ``S``: the hull's rate interval); any other function is
        refused with ``TypeError``."""
        fn = rate_component(fn, "an attitude set")
        hc, hr = self.hull()
        signs = np.array(list(product((-1.0, 1.0), repeat=6)))
        x = hc[0] + signs * hr[0]
        q = qmul(np.broadcast_to(self.q_ref[0], (64, 4)), qexp(x[:, :3]))
        pts = np.concatenate([q, x[:, 3:]], axis=-1)
        vals = np.asarray(fn(pts), dtype=float)
        i, j = int(np.argmin(vals)), int(np.argmax(vals))
        return Extremes(float(vals[i]), pts[i], float(vals[j]), pts[j])

    def attained(self, fn: StateFunction) -> Extremes:
        """Min and max of a :class:`RateComponent` over states of run 0's ``S``: the
        hull's vertices drawn towards ``S``'s own centre (at 1, 1/2, 1/4, 1/8 and 0 of
        the way), those ``S`` holds (a hull vertex may lie outside ``S``, so
        :meth:`extremes`' arguments are not witnesses). ``TypeError`` for other
        functions, ``ValueError`` when no candidate lies in ``S``."""
        fn = rate_component(fn, "an attitude set")
        hc, hr = self.hull()
        signs = np.array(list(product((-1.0, 1.0), repeat=6)))
        centre = np.where(self.lost[0], hc[0], self.z_c[0])
        steps = np.array([1.0, 0.5, 0.25, 0.125, 0.0])[:, None, None]
        x = (centre + steps * (hc[0] + signs * hr[0] - centre)).reshape(-1, 6)
        q = qmul(np.broadcast_to(self.q_ref[0], (len(x), 4)), qexp(x[:, :3]))
        pts = np.concatenate([q, x[:, 3:]], axis=-1)
        held = np.array([self.inside(np.broadcast_to(p, (self.runs, 7)))[0] for p in pts])
        if not held.any():
            raise ValueError("no candidate state of the set was found inside it")
        pts = pts[held]
        vals = np.asarray(fn(pts), dtype=float)
        i, j = int(np.argmin(vals)), int(np.argmax(vals))
        return Extremes(float(vals[i]), pts[i], float(vals[j]), pts[j])


@dataclass(frozen=True)
class SetAttitudeEstimator(Estimator[SetAttitudeBelief, AttitudePrior]):
    """Predict/update/re-centre of ``Z ∩ B`` (module docstring); the set operations are the
    subclass's (:meth:`from_box`, :meth:`affine`, :meth:`strips`)."""

    model: AttitudeModel
    abs_inflation_rad: float = 1e-12
    picard_iterations: int = 8
    # the box estimator B runs alongside (derived from the fields above: not compared)
    box: BoxAttitudeEstimator = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        box = BoxAttitudeEstimator(self.model, self.abs_inflation_rad, self.picard_iterations)
        object.__setattr__(self, "box", box)

    @abstractmethod
    def from_box(self, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(z_c, z_m)`` of the box ``[lo, hi]`` ``(R, 6)``."""

    @abstractmethod
    def radius(self, z_m: FloatArray) -> FloatArray:
        """Per-axis radius ``(R, 6)`` of the interval hull of ``Z`` about its centre."""

    @abstractmethod
    def affine(self, z_c, z_m, A, b, rho) -> tuple[FloatArray, FloatArray]:
        """A set containing :math:`A Z + b \\oplus [-\\rho, \\rho]`."""

    @abstractmethod
    def strips(self, z_c, z_m, lo, hi) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
        """A set containing ``Z ∩ {lo <= x <= hi}`` and the runs found empty."""

    @abstractmethod
    def _belief(self, box, z_c, z_m, **kw: Any) -> SetAttitudeBelief: ...

    def initial(self, prior: AttitudePrior) -> SetAttitudeBelief:
        """The box's first belief, as the set."""
        box = self.box.initial(prior)
        bc, br = box_cr(box)
        return self._belief(box, *self.from_box(bc - br, bc + br))

    def predict(
        self, belief: SetAttitudeBelief, dt_s: float, control: AttitudeControl | None = None
    ) -> SetAttitudeBelief:
        """``S' = (A Z ⊕ b ⊕ rho) ∩ B'`` with ``B'`` the box's prediction."""
        box = self.box.predict(belief.box, dt_s, control)
        if control is None:
            control = AttitudeControl.zero(belief.runs)
        bc, br = box_cr(box)
        lost = ~np.all(np.isfinite(br), -1)  # runs whose box is the whole space
        if lost.all():
            return self._belief(box, 0 * bc, 0 * belief.z_m, **_counts(belief))
        with np.errstate(invalid="ignore"):  # a lost run's box: its set is not used
            fall_c, fall_m = self.from_box(bc - br, bc + br)
        c = qlog(qmul(qinv(belief.q_ref), box.q_ref))
        hc, hr = belief.hull()
        # a lost run (its box the whole space; a lost run stays lost in a prediction)
        # gets a dummy hull, so that its infinite box does not fail the others' maps
        hc, hr = np.where(lost[:, None], 0.0, hc), np.where(lost[:, None], 0.0, hr)
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                A, b, rho = predict_map(self.box, hc, hr, c, control, dt_s)
                z_c, z_m = self.affine(belief.z_c, belief.z_m, A, b, rho)
            bad = ~(np.all(np.isfinite(z_c), -1) & np.all(np.isfinite(z_m), (-2, -1)))
        except (NoEnclosure, FloatingPointError):
            z_c, z_m, bad = fall_c, fall_m, np.ones(belief.runs, bool)
        z_c = np.where(bad[:, None], fall_c, z_c)
        z_m = np.where(bad[:, None, None], fall_m, z_m)
        if lost.any():  # the whole space (the box says so); the set restarts at the update
            z_c = np.where(lost[:, None], 0.0, z_c)
            z_m = np.where(lost[:, None, None], 0.0, z_m)
        return self._belief(box, z_c, z_m, **_counts(belief))

    def update(self, belief: SetAttitudeBelief, measurement: Any) -> SetAttitudeBelief:
        """Six strips of the box's ``B ∩ measurement`` on ``Z``, then the re-centring."""
        if not isinstance(measurement, AttitudeMeasurement):
            raise TypeError("measurement must be an AttitudeMeasurement")
        check_runs(belief.runs, measurement.runs, "measurement")
        lo, hi, box_empty = meet_measurement(self.box, belief.box, measurement)
        box = self.box.update(belief.box, measurement)
        fall_c, fall_m = self.from_box(lo, hi)
        restart = belief.lost | box_empty
        z_c = np.where(restart[:, None], fall_c, belief.z_c)
        z_m = np.where(restart[:, None, None], fall_m, belief.z_m)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            z_c, z_m, set_empty = self.strips(z_c, z_m, lo, hi)
        set_empty &= ~restart
        z_c = np.where(set_empty[:, None], fall_c, z_c)
        z_m = _select(set_empty, fall_m, z_m)
        empty = box_empty | set_empty
        hc, hr = _meet(z_c, self.radius(z_m), lo, hi)
        c = 0.5 * (lo[:, :3] + hi[:, :3])  # the box's re-centring point
        try:
            A, b, rho = recentre_map(c, hc, hr)
            z_c, z_m = self.affine(z_c, z_m, A, b, rho)
        except NoEnclosure:
            bc, br = box_cr(box)
            z_c, z_m = self.from_box(bc - br, bc + br)
        return self._belief(box, z_c, z_m, n_empty=belief.n_empty + empty, last_empty=empty)


def _select(mask: NDArray[np.bool_], a: FloatArray, b: FloatArray) -> FloatArray:
    """``a`` where ``mask`` else ``b`` per run, the narrower padded with zero columns."""
    k = max(a.shape[-1], b.shape[-1])
    a, b = (np.pad(x, ((0, 0), (0, 0), (0, k - x.shape[-1]))) for x in (a, b))
    return np.where(mask[:, None, None], a, b)


def _counts(belief: SetAttitudeBelief) -> dict[str, Any]:
    return {"n_empty": belief.n_empty, "last_empty": belief.last_empty}


def box_cr(box: BoxAttitudeBelief) -> tuple[FloatArray, FloatArray]:
    """Centre and radius ``(R, 6)`` of a box belief."""
    return np.concatenate([box.e_c, box.w_c], -1), np.concatenate([box.e_r, box.w_r], -1)


def _meet(zc, zr, lo, hi) -> tuple[FloatArray, FloatArray]:
    """Centre and radius of ``[zc - zr, zc + zr] ∩ [lo, hi]`` (the box where disjoint)."""
    a, b = np.maximum(zc - zr, lo), np.minimum(zc + zr, hi)
    bad = ~(a <= b)
    a, b = np.where(bad, lo, a), np.where(bad, hi, b)
    return 0.5 * (a + b), 0.5 * (b - a)
