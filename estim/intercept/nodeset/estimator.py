"""The information set of one guidance channel as exact slices at moving nodes.

Seed 003's information set is the set of all states compatible with the data. Its
auxiliary model is *linear* in physical coordinates: with the lateral position
``Y = alpha x`` and ``V = dY/dt``, ``Y'' = v`` (``|v| <= nu``), the range closes at a
constant speed ``e`` (``x' = -e``), an impulse ``k`` adds ``k`` to ``V``, and a bearing
``alpha_m`` says ``|Y - alpha_m x| <= a(x) x``. Scaling by ``u = 1/e`` (``Y~ = Y u``,
``V~ = V u``, time to go ``tau = x u``) removes ``e`` from the bearings::

    Y~'' = v u,   tau' = -1,   |Y~ - alpha_m tau| <= a(tau / u) tau,   V~ += k u

so for ``u`` in a piece ``[u_lo, u_hi]`` the *relaxed* model -- ``v u`` bounded by
``nu u_hi``, the bearing bound taken at the piece's smallest range ``tau / u_hi``,
each impulse's ``k u`` anywhere in ``k [u_lo, u_hi]`` -- contains the true one, and
its information set is a convex body ``K`` in ``(Y~, V~, tau)`` (``a(x) x`` is
concave; every operation is a linear map, a Minkowski sum with a segment or an
intersection with a convex set). With the closing speed known (one piece of zero
width) ``K`` is the seed's information set exactly; a piece of width
``du / u = 2e-3`` (Fig. 5's 57.9..58.1 km/s) relaxes only the impulses' and the
disturbance's scale by that much, and bands can be split (``n_bands``).

The estimator keeps the slices of ``K`` at nodes ``tau_j = label_j - t`` exactly
(each slice is a polygon moved by the seed's own exact operations: bearing strip,
shear, Minkowski sum with the disturbance segment, shift by the impulse), and
bounds ``K`` between nodes by the concavity of its support functions
(:mod:`.bounds`): no state is lost between nodes, and the bound is
tight where the nodes are dense. As bearings pin the range, nodes whose slice
becomes empty are dropped; when fewer than ``min_live_nodes`` remain in a piece, the
piece is re-gridded with ``n_nodes`` new nodes over the surviving interval and the
recorded operations are replayed on them (:meth:`NodeSetEstimator.refine`), so the
nodes follow the surviving range interval.

What the slices do not know: the kinematic term the linear model neglects near the
target (``2 omega^2 x tan alpha``,
:func:`kalman_vs_infoset.estim.intercept.kinematic.kinematic_margin_mps2`) is added to ``nu``
for the whole piece each step, from the piece's own extremes, and an impulse's geometry (``k cos^2
alpha``) widens it; both are common to the piece, which keeps ``K`` convex. Polygons are kept in
``(a, zs) = (alpha / alpha_scale, e_nom (Y~ + V~ tau))``: ``zs`` is the zero-effort miss in metres
for ``e = e_nom``, and the prediction is the unit-determinant shear of the seed.

An update that empties every node (after refinement) contradicts the model: it is
rejected, the set before it kept and the status set to ``"contradiction"``. When every
node has passed under eps the set is empty with status ``"terminal"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from kalman_vs_infoset.estim.base import Estimator, Status
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.kinematic import (
    DIVERGED_W_PER_X,
    MAX_BEARING_RAD,
    STRIP_MARGIN,
    piece_kinematic,
    range_x_interval,
)
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
    check_step,
    impulse_parts,
)
from kalman_vs_infoset.estim.intercept.nodeset import _kernels as _nk
from kalman_vs_infoset.estim.intercept.nodeset.bands import BAND_TRIALS, split_live_bands
from kalman_vs_infoset.estim.intercept.nodeset.belief import NodeSet, evolve
from kalman_vs_infoset.estim.intercept.nodeset.bounds import OpLog
from kalman_vs_infoset.estim.intercept.nodeset.options import DEFAULTS
from kalman_vs_infoset.estim.intercept.nodeset.refine import NodeRefinement
from numpy.typing import NDArray

__all__ = ["NodeSet", "NodeSetEstimator"]

FloatArray = NDArray[np.float64]

#: the kernel's vertex cap when there is none (``max_vertices=None``)
NO_CAP = np.iinfo(np.int64).max


@dataclass(frozen=True)
class NodeSetEstimator(NodeRefinement, Estimator[NodeSet, ChannelPrior]):
    """Set-membership estimator of one channel on exact node slices; configuration only.

    Parameters
    ----------
    model : ChannelModel
        Nominal closing speed ``e_nom``, disturbance bound, measurement bounds, eps.
    closing_speed_mps : (float, float) or None
        Interval of the true closing speed; ``None``: exactly ``e_nom``.
    n_bands : int or None
        Number of bands the closing-speed interval is split into (in ``u = 1/e``);
        ``None``: bands of 0.1 % relative width, at most 8 (1 for a known speed).
    n_nodes : int
        Nodes per piece after (re)gridding.
    split_ratio, max_pieces : float, int
        Before each prediction a piece whose ranges span more than ``split_ratio``
        (largest over smallest) is split in two at a node near its geometric middle,
        while its closing-speed band has fewer than ``max_pieces`` pieces: each piece
        sizes its own kinematic margin (large only near the target) and impulse
        widening.
    min_split_tau_s : float
        The ratio of a piece's times to go is counted from at least this (s) and from
        the time to go at eps: pieces whose states all arrive within about twice this
        are not split. ``0`` (the default): from eps only. Near the target the
        pieces' ratios grow every step, so they split, die and split again; a floor
        of one or two decision steps saves that work, and sizes the kinematic
        margin of the last steps' states over their whole piece (sound, looser
        there; docs/performance.md).
    tighten_rtol, max_inserts : float, int
        After each update, nodes are added (up to ``max_inserts`` rounds, times the
        live closing-speed bands over the initial ones) in the cells where the bounds
        of the zero-effort miss exceed the nodes' exact values by more than
        ``tighten_rtol`` of the set's width (:meth:`NodeSetEstimator.tighten`). Late
        in an unguided approach the end of the feasible interval moves fast, and 4
        rounds (the default before 16) left the set up to 8 % wider than the exact one
        (docs/infoset.md).
    min_live_nodes : int
        A piece with fewer live nodes is re-gridded (at least 4: the bounds between
        nodes need three live nodes in a row).
    alpha_scale_rad : float
        ``a = alpha / alpha_scale_rad`` in the stored polygons.
    kinematic_margin : bool
        The set of the two-body motion: add the bound of the neglected kinematic term
        to ``nu`` (module docstring) and widen a wide prior box by the exact bearing
        and rate of its Cartesian states (:meth:`initial`), and apply an impulse as
        the two-body motion does (``k cos^2(alpha)``: :meth:`_impulse`). Off: the set
        of the auxiliary model alone (``kvi tightness``).
    max_vertices : int or None
        ``None`` (the default): slices are never simplified. Each prediction adds up
        to four vertices to a slice that no bearing clips, so a slice grows with the
        number of steps (the bearings clip most of it; finer steps leave more). An
        integer caps them: a slice
        left with more vertices is outer-simplified to this many (the edges whose
        removal adds the least area go), counted in the belief's ``n_simplified``.
        Each simplified slice still holds its exact slice, but the slices are then
        no longer the slices of one convex body, and the bounds between nodes
        (:mod:`.bounds`) extrapolate secants whose value *falls* as the far node's
        value grows: with a cap the truth can leave the set between nodes (with a
        cap of 8 it did, in Fig. 3 and Fig. 5 runs). A cap is a speed option
        without the guarantee.
    split_bands : bool
        When updates have emptied closing-speed bands, split the live ones in halves
        until as many bands are live as at the start
        (:func:`~.bands.split_live_bands`): with a range
        finder the data pin the speed, and a band's width then dominates the
        interval of the miss.
    max_bands : int
        Most live closing-speed bands.
    impulse_per_piece : bool
        ``True`` (the default): the log keeps each impulse's ``k``, ``dk`` and the least
        ``cos^2`` of the bearing, and a replay forms the interval of the ``V~``
        increment over the node's own piece, so the halves of a band split after an
        impulse lose its spread of ``u`` too (sound: a half's ``u`` lies inside its
        parent's). ``False``: the log keeps the interval per piece as recorded, and a
        band split replays the impulses before it with the parent band's spread of
        ``u``: cheaper where trial splits would pay, looser (docs/infoset.md).
    band_trials : {"auto", "impulse_spread", "extreme_bands"}
        Which bands a trial split tests (:mod:`.bands`). ``"impulse_spread"``: those
        whose spread of the impulses may widen the miss by more than ``tighten_rtol``
        of the set's width; a trial that pays splits that band. ``"extreme_bands"``:
        those, then every few seconds the bands that attain the set's extremes of the
        miss, impulses or not; a trial that pays halves every live band, because the
        relaxation it measured (the band's ``u`` spread over the prior, the
        disturbance and the impulses) is shared by all bands of that width.
        ``"auto"`` (the default): the impulses' trials, and the trials at the extremes
        at every range measurement, where the data pin the closing speed and the set's
        interval of the miss narrows (no clock); with bearings only it is
        ``"impulse_spread"``. With a range finder the extreme trials hold the set
        within 1.03 of the exact width where the impulse trials alone read up to 1.043
        early in the approach; with bearings only they cost 1.1-1.7 times the CPU time
        for no need (docs/infoset.md).
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    closing_speed_mps: tuple[float, float] | None = None
    n_bands: int | None = DEFAULTS.n_bands
    n_nodes: int = DEFAULTS.n_nodes
    min_live_nodes: int = DEFAULTS.min_live_nodes
    split_ratio: float = DEFAULTS.node_split_ratio
    min_split_tau_s: float = DEFAULTS.min_split_tau_s
    max_pieces: int = DEFAULTS.max_pieces
    tighten_rtol: float = DEFAULTS.tighten_rtol
    max_inserts: int = DEFAULTS.max_inserts
    alpha_scale_rad: float = 1.0e-4
    kinematic_margin: bool = DEFAULTS.kinematic_margin
    max_vertices: int | None = DEFAULTS.max_vertices
    split_bands: bool = DEFAULTS.split_bands
    max_bands: int = DEFAULTS.max_bands
    impulse_per_piece: bool = DEFAULTS.impulse_per_piece
    band_trials: str = DEFAULTS.band_trials

    def __post_init__(self) -> None:
        if self.closing_speed_mps is not None:
            lo, hi = self.closing_speed_mps
            if not 0 < lo <= hi:
                raise ValueError("closing_speed_mps must be an interval 0 < lo <= hi")
        if self.n_bands is not None and self.n_bands < 1:
            raise ValueError("n_bands must be >= 1")
        if not 4 <= self.min_live_nodes <= self.n_nodes:
            raise ValueError("need 4 <= min_live_nodes <= n_nodes")
        if not self.alpha_scale_rad > 0:
            raise ValueError("alpha_scale_rad must be positive")
        if not self.split_ratio > 1.0:
            raise ValueError("split_ratio must be > 1 (inf: no splitting)")
        if not self.min_split_tau_s >= 0.0:
            raise ValueError("min_split_tau_s must be >= 0")
        if self.max_pieces < 1:
            raise ValueError("max_pieces must be >= 1")
        if not (self.tighten_rtol > 0 and self.max_inserts >= 0):
            raise ValueError("need tighten_rtol > 0 and max_inserts >= 0")
        if self.max_vertices is not None and self.max_vertices < 8:
            raise ValueError("max_vertices must be None or >= 8")
        if self.band_trials not in BAND_TRIALS:
            raise ValueError(f"band_trials must be one of {', '.join(map(repr, BAND_TRIALS))}")

    # -- construction ----------------------------------------------------------------
    def bands(self) -> tuple[FloatArray, FloatArray]:
        """``u_lo, u_hi`` of each band (``u = 1/e``, equal pieces of the interval)."""
        # every closing speed the truth reaches (the interval, widened by its drift)
        e_lo, e_hi = self.model.drifted_speeds(self.closing_speed_mps)
        # a band relaxes the impulses' and the disturbance's scale by its relative
        # width: bands of 0.1 % by default (Fig. 5's 57.9..58.1 km/s: 4), at most 8
        n = self.n_bands or int(np.clip(np.ceil((e_hi / e_lo - 1.0) / 1e-3), 1, 8))
        edges = np.linspace(1.0 / e_hi, 1.0 / e_lo, n + 1) if e_lo < e_hi else np.full(2, 1 / e_lo)
        return edges[:-1], edges[1:]

    @cached_property
    def start_bands(self) -> int:
        """How many bands :meth:`bands` makes (asked every update: computed once)."""
        return len(self.bands()[0])

    def initial(self, prior: ChannelPrior | None = None, **box) -> NodeSet:
        """The exact slices of the a-priori box at ``n_nodes`` labels per piece (the
        prior's closing speed is not used: the bands take ``closing_speed_mps``;
        ``initial(lateral_m=..., lateral_vel_mps=..., x_m=...)`` is short for
        ``initial(ChannelPrior(...))``).

        At label ``tau0`` a state of piece ``[u_lo, u_hi]`` has ``x0 = tau0 / u`` in the
        box, so ``u`` ranges over ``U = [tau0/x_hi, tau0/x_lo] & [u_lo, u_hi]`` and the
        slice is ``{u (y, Vy)}`` over ``U`` and the box: the convex hull of the box's
        corners scaled by both ends of ``U`` (exact; it is the slice of a convex body).
        With ``kinematic_margin`` (the set of the two-body motion) the box is first
        widened where the exact bearing and line-of-sight rate of a Cartesian state
        leave it (:meth:`ChannelPrior.auxiliary_box`: only for boxes wide against their
        range); a set of the auxiliary model takes the box as it is.
        """
        prior = ChannelPrior(**box) if prior is None else prior
        u_lo, u_hi = self.bands()
        if self.kinematic_margin:
            # the box of the coordinates the slices take, holding every Cartesian state
            prior = prior.auxiliary_box(1.0 / float(u_lo.min()))
        prior = prior.drifted(self.model)
        (y0, y1), (v0, v1), (xa, xb) = prior.lateral_m, prior.lateral_vel_mps, prior.x_m
        hard_lo, hard_hi = xa * u_lo, xb * u_hi
        # a known range (a point box) is one node
        labels = [
            np.unique(np.linspace(lo, hi, self.n_nodes))
            for lo, hi in zip(hard_lo, hard_hi, strict=True)
        ]
        piece = np.repeat(np.arange(len(u_lo)), [len(lab) for lab in labels])
        boxes = ((y0, y1), (v0, v1), (xa, xb))
        empty = ConvexPolygons(np.zeros((0, 2)), np.zeros(1, dtype=np.int64))
        base = NodeSet(
            self.model, u_lo, u_hi, np.zeros(0, np.int64), np.zeros(0), empty, hard_lo,
            hard_hi, 0.0, OpLog.empty(len(u_lo)), boxes, self.alpha_scale_rad,
        )  # fmt: skip
        label = np.concatenate(labels)
        return evolve(base, piece=piece, label_s=label, polygons=self._prior(base, piece, label))

    def _prior(self, s: NodeSet, piece: NDArray[np.int64], label: FloatArray) -> ConvexPolygons:
        """The prior slices at ``label`` (see :meth:`initial`)."""
        (y0, y1), (v0, v1), (xa, xb) = s.prior
        xy, off = _nk.prior_points(
            np.ascontiguousarray(label, dtype=float), s.u_lo[piece], s.u_hi[piece],
            *(float(v) for v in (y0, y1, v0, v1, xa, xb)), self.alpha_scale_rad, s.e_nom,
        )  # fmt: skip
        return ConvexPolygons._make(*_k.convex_hulls(xy, off))

    # -- Estimator interface ---------------------------------------------------------
    def update(self, belief: NodeSet, measurement: Bearing | Range) -> NodeSet:
        """Intersect every node with a bearing strip, or drop the nodes outside a
        range interval; re-grid a piece left with too few nodes; reject (status
        ``"contradiction"``) an update that leaves nothing."""
        if belief.is_empty:
            return belief
        nb_ = len(belief.u_lo)
        if isinstance(measurement, Bearing):
            op = OpLog.one(_nk.BEARING, nb_, measurement.alpha_rad)
        elif isinstance(measurement, Range):
            op = OpLog.one(_nk.RANGE, nb_, *range_x_interval(self.model, measurement))
        else:
            raise TypeError(f"unsupported measurement {type(measurement).__name__}")
        out = self.refine(self._record(belief, op), before=belief)
        if not out.is_empty and self.split_bands:
            trials = self.band_trials
            if trials == "auto":  # the extremes are tried where a range pins the set
                trials = "at_range" if isinstance(measurement, Range) else "impulse_spread"
            out = split_live_bands(
                self, out, self.start_bands, self.max_bands, self.tighten_rtol, trials
            )
        if not out.is_empty:
            out = self.tighten(out)
        if out.is_empty:
            return evolve(
                belief, status=Status.CONTRADICTION, contradictions=belief.contradictions + 1
            )
        return out

    def _impulse(self, s: NodeSet, control: float | Impulse, per: FloatArray) -> OpLog:
        """The operation of an impulse ``k`` (m/s, relative velocity): ``V += k
        cos^2(alpha)``, i.e. ``V~ += k u cos^2(alpha)`` with ``u`` anywhere in the piece
        and ``alpha`` up to the piece's largest bearing (the two-body motion's change;
        without ``kinematic_margin``, the auxiliary model's ``V += k``); an
        :class:`~estim.intercept.model.Impulse` known to ``+-dk`` adds ``dk u_hi`` either way.
        The per-piece bounds of ``w`` in ``per`` move by what the impulse can do."""
        k, dk = impulse_parts(control)
        # per piece (compiled: a handful of numbers, every step): with sin^2 of the
        # largest bearing, dV~ in [min, max](k u_lo (1 - sin^2), k u_hi) -+ dk u_hi;
        # zs moves by e_nom tau dV~ with tau in [tau_lo, tau_hi]; w = (e/e_nom)^2 zs
        # (the auxiliary model alone, without the kinematic margin, has V += k exactly,
        # whatever the bearing: the kernel sees bearings of 0, i.e. cos^2 = 1, and only
        # the bounds of w move in ``per``)
        geometry = per
        if not self.kinematic_margin:
            geometry = per.copy()
            geometry[:, 2:4] = 0.0
        lo, hi, cos2 = _nk.impulse_interval(geometry, s.u_lo, s.u_hi, s.e_nom, float(k), float(dk))
        if geometry is not per:  # the kernel moved the copy's bounds of w
            per[:, :2] = geometry[:, :2]
        if self.impulse_per_piece:  # k, dk and cos^2: replays form the interval per piece
            return OpLog.one(_nk.IMPULSE, len(lo), pa=k, pb=dk, q_lo=cos2, q_hi=hi)
        return OpLog.one(_nk.IMPULSE, len(lo), q_lo=lo, q_hi=hi)

    def predict(
        self, belief: NodeSet, dt_s: float, control: float | Impulse | None = None
    ) -> NodeSet:
        """Apply the impulse ``control`` (at the step's start; :meth:`_impulse`), then
        move every node over ``dt_s`` (exact shear, disturbance segment), drop the
        nodes under eps, split wide pieces and re-grid thinned ones.

        The disturbance of each piece is ``nu`` plus the interval of the kinematic
        term over its states (:func:`..kinematic.kinematic_interval`),
        sized from the belief's own summary (the impulse's effect on ``w`` added), so
        a step computes the bounds between nodes once; impulse and prediction are
        one compiled call.
        """
        check_step(dt_s)
        if belief.is_empty:
            return belief
        # bounds of w, alpha and tau per piece
        per = belief._summary["per_piece"].copy()
        ops = OpLog.empty(len(belief.u_lo))
        k, dk = impulse_parts(control) if control is not None else (0.0, 0.0)
        if control is not None and (k != 0.0 or dk != 0.0):  # (k, dk) = 0 without control
            ops = self._impulse(belief, control, per)
        # each band applies the impulse for all its u: a spread of |k| du in V~, up to
        # about |k| tau rel in w (the trial splits of bands.py weigh it)
        tau = per[:, 5][np.isfinite(per[:, 5])]
        moment = belief.impulse_moment_m + (abs(k) * float(tau.max()) if len(tau) else 0.0)
        s, per, ops = self._split(belief, per, ops)
        v_lo = np.full(len(s.u_lo), -self.model.nu_mps2)
        v_hi = -v_lo
        if self.kinematic_margin:
            k_lo, k_hi = self._kinematic(s, per, dt_s)
            v_lo, v_hi = v_lo + k_lo, v_hi + k_hi
            x_max = np.maximum(per[:, 5], 0.0) / s.u_lo
            w_abs = np.maximum(np.abs(per[:, 0]), np.abs(per[:, 1]))
            if not np.all((w_abs <= DIVERGED_W_PER_X * x_max) | ~np.isfinite(per[:, 4])):
                empty = s.polygons.clip_slab(0, np.full(s.polygons.n, np.inf), 0.0)
                return evolve(s, polygons=empty, status=Status.DIVERGED)
        # v u for u in [u_lo, u_hi]
        q_lo = np.minimum(v_lo * s.u_lo, v_lo * s.u_hi)
        q_hi = np.maximum(v_hi * s.u_lo, v_hi * s.u_hi)
        ops = ops + OpLog.one(_nk.PREDICT, len(q_lo), dt_s, q_lo=q_lo, q_hi=q_hi)
        out = self.refine(self._record(s, ops, impulse_moment_m=moment), before=s)
        if out.is_empty and out.status == Status.OK:
            return evolve(out, status=Status.TERMINAL)
        return out

    # -- the operations (applied to the set, and replayed on new nodes) -----------------
    def _record(self, s: NodeSet, op: OpLog, **fields) -> NodeSet:
        polys, t, hard_lo, hard_hi, n_simpl = self._apply(
            s, s.piece, s.label_s, s.polygons, op, s.t_s
        )
        return evolve(
            s, polygons=polys, t_s=t, log=s.log + op, hard_lo_s=hard_lo, hard_hi_s=hard_hi,
            status=Status.OK, n_simplified=s.n_simplified + n_simpl, **fields,
        )  # fmt: skip

    def _apply(self, s: NodeSet, piece, label, polys: ConvexPolygons, ops: OpLog, t: float):
        """Operations ``ops`` on the nodes ``(piece, label)`` from time ``t``; returns the
        new polygons, time, hard label limits and the number of slices outer-simplified
        (compiled: :func:`_nk.apply_ops`)."""
        bb = self.model.bearing_bound
        xy, off, t, hard_lo, hard_hi, n_simpl = _nk.apply_ops(
            polys.xy, polys.offsets, np.ascontiguousarray(label, dtype=float),
            np.ascontiguousarray(piece, dtype=np.int64), s.u_lo, s.u_hi, s.hard_lo_s,
            s.hard_hi_s, float(t), *ops.parts(), self.alpha_scale_rad, s.e_nom,
            self.model.eps_sets_m, bb.end_rad, bb.start_rad, bb.ref_range_m, STRIP_MARGIN,
            NO_CAP if self.max_vertices is None else self.max_vertices, self.impulse_per_piece,
        )  # fmt: skip
        return ConvexPolygons._make(xy, off), t, hard_lo, hard_hi, n_simpl

    # -- piece-wide quantities ----------------------------------------------------------
    def _kinematic(self, s: NodeSet, per: FloatArray, dt_s: float) -> tuple[FloatArray, ...]:
        """Interval of the kinematic term of each piece over the next step (m/s^2), from
        the per-piece bounds ``per`` of ``w``, ``alpha`` and ``tau``; pieces without
        cells get zero."""
        # x in [(tau_lo - dt) / u_hi (at least eps), tau_hi / u_lo] over the step;
        # compiled (kinematic_interval per piece: a handful of numbers every step)
        return piece_kinematic(
            per, s.u_lo, s.u_hi, float(dt_s), self.model.eps_sets_m, s.e_nom, self.model.nu_mps2,
            MAX_BEARING_RAD,
        )  # fmt: skip


def warm_up() -> None:
    """Load the node set's compiled kernels in this process (a few steps of a small
    set with a closing-speed interval: bearings, ranges, an impulse, the extremes, the
    forecast miss at the slices' vertices and the containment test). Forked Monte
    Carlo workers then inherit them instead of each loading or compiling them again."""
    from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss

    model = ChannelModel()
    est = NodeSetEstimator(model, closing_speed_mps=(57.9e3, 58.1e3))
    b = est.initial(lateral_m=(-1e3, 1e3), lateral_vel_mps=(-100.0, 100.0), x_m=(7e5, 9e5))
    for k in range(3):
        x = 8e5 - 58e3 * 0.5 * k
        b = est.update(b, Bearing(1e-4))
        b = est.update(b, Range(x, off_axis_rad=0.0))
        b.extremes(MissForecast(model))
        b.extremes(ZeroEffortMiss(model))
        b.attained(MissForecast(model))
        b.contains(np.array([1e-4, 0.0, x]))
        b = est.predict(b, 0.5, 1.0)
