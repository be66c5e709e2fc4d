"""Refinement of the node set: where nodes are added, and how (:mod:`.estimator`).

New nodes get exact slices by replaying the recorded operations on the prior
(:meth:`NodeRefinement._exact_slices`). Nodes are added

* when a piece is down to a few live nodes (:meth:`NodeRefinement.refine`): its
  feasible labels form an interval inside the bracket of the live run, whose
  longest cells are bisected (a piece emptied by a bearing is searched for the
  states the bearing left between its nodes: :meth:`NodeRefinement._search`);
* where the bounds of the zero-effort miss are loosest (:meth:`NodeRefinement.tighten`);
* and pieces are split where their ranges span too much (:meth:`NodeRefinement._split`),
  so that each sizes its own kinematic margin.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.kinematic import STRIP_MARGIN
from kalman_vs_infoset.estim.intercept.model import ChannelModel
from kalman_vs_infoset.estim.intercept.nodeset import _geometry as _ng
from kalman_vs_infoset.estim.intercept.nodeset import _kernels as _nk
from kalman_vs_infoset.estim.intercept.nodeset.belief import NodeSet, evolve
from kalman_vs_infoset.estim.intercept.nodeset.bounds import OpLog
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: refinement stops when the new nodes are closer than this (relative to tau): about
#: 70 ulps of a label. A feasible range that collapses at an end of the prior box (a
#: truth at its corner, errors at their bound) can be a sliver of 2e-13 of the labels:
#: 1e-12 stopped with fewer than three live nodes there, and the bound of the miss
#: across their cell was unbounded (cases 70191 and 70811 of tests/fuzz_tightness.py).
#: Closer nodes carry more rounding in their secants; MAX_SECANT_REACH (._geometry)
#: bounds how far such a secant is extrapolated.
MIN_SPACING_REL = 1e-14

#: a new node this close (relative to its label) to another of its piece is a twin of
#: it, and is not added (:func:`_twins`); well under the refinement's spacing above
DUPLICATE_REL = 1e-15


class NodeRefinement:
    """The refinement half of :class:`.estimator.NodeSetEstimator` (a mixin: it uses
    the estimator's options and its ``_apply`` and ``_prior``)."""

    # what the mixin uses of the estimator (declared there, as dataclass fields)
    model: ChannelModel
    n_nodes: int
    min_live_nodes: int
    split_ratio: float
    min_split_tau_s: float
    max_pieces: int
    tighten_rtol: float
    max_inserts: int
    alpha_scale_rad: float

    if TYPE_CHECKING:  # the estimator's methods, as the type checker sees them

        def _prior(
            self, s: NodeSet, piece: NDArray[np.int64], label: FloatArray
        ) -> ConvexPolygons: ...

        def _apply(
            self, s: NodeSet, piece: Any, label: Any, polys: ConvexPolygons, ops: OpLog, t: float
        ) -> tuple[ConvexPolygons, float, FloatArray, FloatArray, int]: ...

        @property
        def start_bands(self) -> int: ...

    def refine(self, s: NodeSet, before: NodeSet | None = None) -> NodeSet:
        """:meth:`_refine_pieces`, then drop the nodes and pieces that bound nothing
        (pieces are renumbered only here, after every piece was visited)."""
        return _compact(self._refine_pieces(s, before))

    def _refine_pieces(self, s: NodeSet, before: NodeSet | None = None) -> NodeSet:
        """Add nodes to every piece with fewer than ``min_live_nodes`` live ones.

        The piece's feasible labels form an interval (the body is convex) inside the
        bracket of its live run: from the dead node below it (or the hard limit) to the
        dead node above. New nodes (exact slices: the prior, then every recorded
        operation) bisect the longest cells of the bracket -- the end cells, where
        the feasible interval ends, among them -- until the piece has ``min_live_nodes``
        plus two; a piece down to one live node is re-gridded with ``n_nodes`` (the live
        node kept when none of the new ones holds a state: its states may be a sliver
        between them, and an empty piece is dropped). A piece
        emptied by a bearing is searched (:meth:`_search`) in the bracket it had
        ``before``; one emptied by a range interval or the threshold is re-gridded where
        that bracket meets the new hard limits (the feasible interval, if any is left,
        reaches one of their ends, which are nodes of the new grid). Dead nodes outside
        the brackets are dropped.
        """
        live_per_piece = np.bincount(s.piece[s.live], minlength=len(s.u_lo))
        if live_per_piece.min() >= self.min_live_nodes:
            return s  # every piece has its live nodes (the loop below would break at once)
        for p in range(len(s.u_lo)):
            searched = False
            for _ in range(self._max_rounds()):
                n_live = int((s.live & (s.piece == p)).sum())
                if n_live >= self.min_live_nodes:
                    break
                if n_live == 0:
                    had = before is not None and bool((before.live & (before.piece == p)).any())
                    if not had or searched:
                        break
                    assert before is not None  # had: before holds live nodes
                    lo, hi = self._bracket(before, p)
                    if int(s.log.kinds[-1]) == _nk.BEARING:
                        if not self._strip_misses(before, p, float(s.log.pa[-1])):
                            held = before.label_s[before.live & (before.piece == p)]
                            s = self._search(s, p, lo, hi, held)
                        break
                    # a range interval or the threshold cut every node off: what is
                    # left lies where the feasible interval (inside the old bracket)
                    # crosses the new hard limits, and reaches one of their ends
                    lo, hi = max(lo, s.hard_lo_s[p]), min(hi, s.hard_hi_s[p])
                    if not hi >= lo:
                        break
                    s = self._regrid(s, p, np.linspace(lo, hi, self.n_nodes))
                    searched = True
                    continue
                lo, hi = self._bracket(s, p)
                lo, hi = max(lo, s.hard_lo_s[p]), min(hi, s.hard_hi_s[p])
                if not hi - lo > MIN_SPACING_REL * max(abs(hi), 1.0) * self.n_nodes:
                    break
                if n_live == 1:
                    grid = np.linspace(lo, hi, self.n_nodes)
                    out = self._regrid(s, p, grid)
                    if not (out.live & (out.piece == p)).any():
                        # the states lie between the new nodes (a sliver around the
                        # live node, narrower than the grid's spacing): dropping the
                        # live node would drop them, so it stays, and the next round
                        # re-grids the narrower bracket its new dead neighbours leave
                        out = self._regrid_keeping_live(s, p, grid)
                    s = out
                    continue
                mine = (s.piece == p) & (s.label_s >= lo) & (s.label_s <= hi)
                knots = np.unique(np.r_[lo, s.label_s[mine], hi])
                labels = _bisect_longest(knots, self.min_live_nodes + 2 - n_live)
                piece = np.full(len(labels), p)
                polys = self._exact_slices(s, piece, labels)
                s = _merge(s, np.ones(s.polygons.n, dtype=bool), piece, labels, polys)
        return s

    def _max_rounds(self) -> int:
        """Rounds of :meth:`_refine_pieces` per piece: enough for a piece down to one
        live node to be re-gridded until its bracket reaches ``MIN_SPACING_REL`` (each
        re-grid narrows it at least ``(n_nodes - 1) / 2`` times), plus a few bisections.
        A fixed 4 left a thin piece with one live node and unbounded cells beside it
        (kp_fig5, ``n_nodes = 6``, seed 5, run 38 of 50, at 99.5 s)."""
        shrink = max((self.n_nodes - 1) / 2.0, 1.5)
        return 4 + int(np.ceil(np.log(1.0 / MIN_SPACING_REL) / np.log(shrink)))

    def _search(self, s: NodeSet, p: int, lo: float, hi: float, held: FloatArray) -> NodeSet:
        """Find the states of piece ``p`` that the last bearing left between its nodes.

        Before the last bearing the piece had states in ``[lo, hi]``, at the labels
        ``held`` among others. How far a slice misses the bearing's strip (in ``Y~``:
        ``min Y~ - (alpha_m + a) tau`` or ``(alpha_m - a) tau - max Y~``) is convex in
        ``tau`` (the body is convex and ``a(x) x`` concave), so if no node of a fine
        grid meets the strip, any states left lie next to the node that misses it
        least: the search narrows to that node's neighbours, down to a spacing of
        ``MIN_SPACING_REL``. The piece is empty when nothing is found. A grid none of
        whose nodes held states before the bearing (a sliver between its nodes) says
        nothing: it is searched again with the labels known to hold some added.
        """
        head = OpLog(*(a[:-1] for a in s.log.parts()))
        alpha_m = float(s.log.pa[-1])
        retry = False
        for _ in range(12):  # each level narrows the bracket ~(n_nodes - 1) / 2 times
            labels = np.linspace(lo, hi, self.n_nodes)
            if retry:
                labels = np.unique(np.r_[labels, held[(held > lo) & (held < hi)]])
            if not hi - lo > MIN_SPACING_REL * max(abs(hi), 1.0) * self.n_nodes:
                break
            piece = np.full(len(labels), p)
            polys, t, _, _, _ = self._apply(
                s, piece, labels, self._prior(s, piece, labels), head, 0.0
            )
            out = self._regrid(s, p, labels, polys_before_last=(polys, t))
            if (out.live & (out.piece == p)).any():
                return self._refine_pieces(out)
            tau = labels - t
            bb = self.model.bearing_bound
            half = bb(tau / s.u_hi[p]) * (1.0 + STRIP_MARGIN) + STRIP_MARGIN * self.alpha_scale_rad
            bounds = polys.bounds() * self.alpha_scale_rad  # a_min, zs_min, a_max, zs_max
            miss = np.maximum(bounds[:, 0] - (alpha_m + half), (alpha_m - half) - bounds[:, 2])
            miss = np.where(np.isnan(miss), np.inf, miss * tau)
            k = int(np.argmin(miss))
            if not np.isfinite(miss[k]):
                if retry or not ((held > lo) & (held < hi)).any():
                    break
                retry = True  # this level again, with the labels that held states
                continue
            retry = False
            held = labels[k : k + 1]  # it held states before the bearing
            lo, hi = labels[max(k - 1, 0)], labels[min(k + 1, len(labels) - 1)]
        return s

    def _strip_misses(self, before: NodeSet, p: int, alpha_m: float) -> bool:
        """Whether the bearing strip at ``alpha_m`` misses every cell of piece ``p`` of
        the set ``before`` it: each cell's bounds of the bearing (sound, from the
        bounds between nodes) lie outside the strip at its widest over the cell (the
        bound at the cell's smallest range), or, for the cells where they do not, the
        strip misses the cell at each of its times to go (:func:`_strip_misses_along`).
        Then the piece is empty, and the search's replays (:meth:`_search`, which
        would find nothing) are skipped."""
        sm = before._summary
        cells = np.flatnonzero(sm["piece"] == p)
        if not len(cells):
            return False
        tau_lo = np.maximum(sm["span"][cells, 0], 0.0)
        half = self.model.bearing_bound(tau_lo / before.u_hi[p]) * (1.0 + STRIP_MARGIN)
        half = half + STRIP_MARGIN * self.alpha_scale_rad
        a = sm["alpha"][cells]
        missed = (a[:, 0] > alpha_m + half) | (a[:, 1] < alpha_m - half)
        if missed.all():
            return True
        # the cells left, time to go by time to go (most searches found nothing there)
        rest = cells[~missed]
        return bool(_strip_misses_along(before, rest, alpha_m, half[~missed]).all())

    @staticmethod
    def _bracket(s: NodeSet, b: int) -> tuple[float, float]:
        idx = np.flatnonzero(s.piece == b)
        live = np.flatnonzero(s.live[idx])
        first, last = idx[live[0]], idx[live[-1]]
        lo = s.label_s[first - 1] if first - 1 >= idx[0] else s.hard_lo_s[b]
        hi = s.label_s[last + 1] if last + 1 <= idx[-1] else s.hard_hi_s[b]
        return float(lo), float(hi)

    def _regrid(
        self, s: NodeSet, b: int, labels: FloatArray, polys_before_last=None, keep=None
    ) -> NodeSet:
        """Piece ``b`` with new nodes at ``labels``: the prior, then the whole log (or
        only its last operation on ``polys_before_last = (polygons, t)``). Its old nodes
        go, but those in ``keep`` (a boolean mask over the nodes, default none)."""
        piece = np.full(len(labels), b)
        if polys_before_last is None:
            polys = self._exact_slices(s, piece, labels)
        else:
            last = OpLog(*(a[-1:] for a in s.log.parts()))
            polys, _, _, _, _ = self._apply(s, piece, labels, polys_before_last[0], last,
                                         polys_before_last[1])  # fmt: skip
        others = s.piece != b
        return _merge(s, others if keep is None else others | keep, piece, labels, polys)

    def _regrid_keeping_live(self, s: NodeSet, b: int, grid: FloatArray) -> NodeSet:
        """Piece ``b`` re-gridded at ``grid`` (sorted), its live nodes kept with their
        slices (a grid label equal to one of theirs is not replayed again)."""
        mine = s.live & (s.piece == b)
        return self._regrid(s, b, np.unique(grid[~np.isin(grid, s.label_s[mine])]), keep=mine)

    def _exact_slices(self, s: NodeSet, piece: NDArray[np.int64], labels: FloatArray):
        """The slices at new nodes: the prior, then every recorded operation."""
        polys, _, _, _, _ = self._apply(s, piece, labels, self._prior(s, piece, labels), s.log, 0.0)
        return polys

    def tighten(self, s: NodeSet) -> NodeSet:
        """Add nodes where the bounds of the zero-effort miss are loosest.

        The extremes of ``w`` over the set sit in one cell each; where such a bound
        exceeds the exact values at the cell's two nodes by more than
        ``tighten_rtol`` of the set's width (typically a cell at the end of the
        surviving range, bounded from one side only), a node is added at the cell's
        middle, three at its quarters for a cell with a dead end (exact, by replay),
        for up to ``max_inserts`` rounds per call, times the number of closing-speed
        bands over the number the estimator started with (split bands each have their
        own end cells to locate).
        """
        # the budget grows with the closing-speed bands split off since the start: each
        # live band has its own cells at the ends of the feasible interval to locate
        n_bands = len(set(zip(s.u_lo.tolist(), s.u_hi.tolist(), strict=True)))
        start = max(1, self.start_bands)
        for _ in range(self.max_inserts * max(1, -(-n_bands // start))):
            sm = s._summary
            w = sm["w"]
            if len(w) == 0:
                break
            width = float(w[:, 1].max() - w[:, 0].min())
            new_piece, new_label = [], []
            for c, side in ((int(np.argmax(w[:, 1])), 1), (int(np.argmin(w[:, 0])), 0)):
                i, j = sm["table"][c, 1], sm["table"][c, 2]
                p = int(sm["piece"][c])
                big = (1.0 / (s.u_lo[p] * s.e_nom)) ** 2
                small = (1.0 / (s.u_hi[p] * s.e_nom)) ** 2
                if side == 1:
                    node = max(_zs_extent(s, i)[1], _zs_extent(s, j)[1])
                    node = node * (big if node > 0 else small)
                    slack = w[c, 1] - node
                else:
                    node = min(_zs_extent(s, i)[0], _zs_extent(s, j)[0])
                    node = node * (big if node < 0 else small)
                    slack = node - w[c, 0]
                lo, hi = sm["span"][c]
                tiny = MIN_SPACING_REL * max(abs(hi), 1.0)
                if slack > self.tighten_rtol * width and hi - lo > tiny:
                    # a cell with a dead end is bounded from one side only: three nodes
                    # at once locate the end of the feasible interval four times closer
                    edge = not (s.live[i] and s.live[j])
                    for f in (0.25, 0.5, 0.75) if edge else (0.5,):
                        new_piece.append(p)
                        new_label.append(lo + f * (hi - lo) + s.t_s)
            if not new_piece:
                break
            pairs = sorted(set(zip(new_piece, new_label, strict=True)))
            piece = np.array([q for q, _ in pairs], dtype=np.int64)
            labels = np.array([lab for _, lab in pairs])
            polys = self._exact_slices(s, piece, labels)
            s = _merge(s, np.ones(s.polygons.n, dtype=bool), piece, labels, polys)
        return s

    def _split(self, s: NodeSet, per: FloatArray, ops: OpLog) -> tuple[NodeSet, FloatArray, OpLog]:
        """Split wide pieces in two at a live node near their geometric middle (the
        node is kept in both halves: each half's slices there are exact). ``per`` (the
        per-piece summary) and the pending ``ops`` get a copy of the split piece's row
        and column."""
        # the pieces wide enough to split, found in one vector operation (a piece's
        # row of ``per`` does not change when others split); each is then checked in
        # order, as the splits before it change the band's count of pieces
        # counted from eps at least (and from min_split_tau_s: states that arrive
        # within a step or two need no margin of their own)
        tau_lo = np.maximum(
            np.maximum(per[:, 4], self.model.eps_sets_m * s.u_lo), self.min_split_tau_s
        )
        wide = np.isfinite(per[:, 4]) & (per[:, 5] > self.split_ratio * tau_lo)
        for p in np.flatnonzero(wide).tolist():
            lo, hi = float(tau_lo[p]), float(per[p, 5])
            if np.count_nonzero(s.u_lo == s.u_lo[p]) >= self.max_pieces:
                continue  # this closing-speed band has its pieces
            idx = np.flatnonzero((s.piece == p) & s.live)
            if len(idx) < 3:
                continue
            mid = np.sqrt(lo * hi) + s.t_s
            j = idx[1 + int(np.argmin(np.abs(s.label_s[idx[1:-1]] - mid)))]
            s = _split_at(s, p, j)
            per = np.vstack([per, per[p]])
            ops = ops.with_copied_column(p)
        return s, per, ops


def _strip_misses_along(before: NodeSet, cells, alpha_m: float, half) -> NDArray[np.bool_]:
    """Whether the bearing strip ``|Y~ / tau - alpha_m| <= half`` misses each of the
    ``cells`` of ``before``'s summary at every ``tau`` of the cell: the cell's ``Y~``
    lies between the secants of its nodes' extents in ``Y~`` (the bounds between
    nodes, each valid over the whole cell), so a state at ``tau`` in the strip needs
    ``min(up lines)(tau) >= (alpha_m - half) tau`` and ``max(down lines)(tau) <=
    (alpha_m + half) tau``: each the set where lines are non-negative, an interval.
    The cell is missed when the two leave no ``tau`` of it. (The cell's bounds of the
    bearing, which :meth:`NodeRefinement._strip_misses` tries first, take ``Y~``'s
    bound over the whole cell at either end.) A cell bounded from neither side is not
    missed; each line gets a margin of 1e-8 of the values it spans (rounding)."""
    sm = before._summary
    table, tau4, span = sm["table"][cells], sm["tau4"][cells], sm["span"][cells]
    ext = before.polygons.bounds()[:, [0, 2]] * before.alpha_scale_rad  # a_min, a_max
    # (a node's extent in Y~ = a tau alpha_scale; live nodes have tau > 0)
    y = np.where(((table >= 0) & (tau4 > 0))[..., None], ext[table] * tau4[..., None], np.nan)
    lo, hi = span[:, 0].copy(), span[:, 1].copy()
    bounded = np.zeros(len(cells), dtype=bool)
    for near, far in ((1, 0), (2, 3)):  # the secant through nodes i-1, i; i+2, i+1
        dt = tau4[:, near] - tau4[:, far]
        ok = np.isfinite(y[:, near, 0]) & np.isfinite(y[:, far, 0]) & (dt != 0.0)
        dt = np.where(ok, dt, 1.0)
        reach = np.maximum(np.abs(span[:, 1] - tau4[:, near]), np.abs(span[:, 0] - tau4[:, near]))
        for k, side in ((1, 1.0), (0, -1.0)):  # Y~ up to the max line, down to the min
            f_near, f_far = y[:, near, k], y[:, far, k]
            slope = (f_near - f_far) / dt
            c0 = f_near - slope * tau4[:, near]
            margin = 1e-8 * (np.abs(f_near) + np.abs(f_far) + np.abs(slope) * reach)
            # side * (line(tau) - strip edge(tau)) + margin >= 0, as c + g tau >= 0
            edge = alpha_m - side * half
            c = side * c0 + margin
            g = side * (slope - edge)
            with np.errstate(divide="ignore", invalid="ignore"):
                root = -c / g
            lo = np.where(ok & (g > 0), np.maximum(lo, root), lo)
            hi = np.where(ok & (g < 0), np.minimum(hi, root), hi)
            hi = np.where(ok & (g == 0) & (c < 0), -np.inf, hi)
        bounded |= ok
    return bounded & ~(lo <= hi)


def _bisect_longest(knots: FloatArray, k: int) -> FloatArray:
    """``k`` new points, each the middle of the longest gap left between ``knots``."""
    gaps = [(float(b - a), float(a), float(b)) for a, b in zip(knots[:-1], knots[1:], strict=True)]
    out = []
    for _ in range(k):
        i = max(range(len(gaps)), key=lambda j: gaps[j][0])
        _, a, b = gaps.pop(i)
        mid = 0.5 * (a + b)
        out.append(mid)
        gaps += [(mid - a, a, mid), (b - mid, mid, b)]
    return np.array(sorted(out))


def _compact(s: NodeSet) -> NodeSet:
    """Drop the dead nodes that bracket no live run (each piece's feasible labels are
    an interval: only the dead nodes next to it bound it)."""
    live = s.live
    if live.all():
        return s
    same = s.piece[1:] == s.piece[:-1]
    near = live.copy()
    near[1:] |= live[:-1] & same  # the dead node just above a live one
    near[:-1] |= live[1:] & same  # and just below
    if not near.all():
        s = evolve(
            s, piece=s.piece[near], label_s=s.label_s[near], polygons=s.polygons.select(near)
        )
    return _drop_empty_pieces(s)


def _drop_empty_pieces(s: NodeSet) -> NodeSet:
    """Remove the pieces left without nodes (their band and label interval hold no
    state any more), renumbering the rest; the set keeps at least one piece."""
    used = np.zeros(len(s.u_lo), dtype=bool)
    used[s.piece] = True
    if used.all() or not used.any():
        return s
    new_index = np.cumsum(used) - 1
    log = s.log
    return evolve(
        s, piece=new_index[s.piece], u_lo=s.u_lo[used], u_hi=s.u_hi[used],
        hard_lo_s=s.hard_lo_s[used], hard_hi_s=s.hard_hi_s[used],
        log=OpLog(log.kinds, log.pa, log.pb, np.ascontiguousarray(log.q_lo[:, used]),
                  np.ascontiguousarray(log.q_hi[:, used])),  # C order (one compiled type)
    )  # fmt: skip


def _zs_extent(s: NodeSet, i: int) -> tuple[float, float]:
    """Smallest and largest ``zs`` of node ``i``'s polygon (inf, -inf when empty)."""
    return _ng.zs_extent(s.polygons.xy, s.polygons.offsets, int(i))


def _merge(s: NodeSet, keep, piece, labels, polys: ConvexPolygons) -> NodeSet:
    """``s`` with its nodes ``keep`` (a boolean mask) and the new nodes ``(piece, labels,
    polys)``, sorted by piece, then label."""
    kept = np.flatnonzero(keep)
    all_piece = np.concatenate([s.piece[kept], piece])
    all_label = np.concatenate([s.label_s[kept], labels])
    order = np.lexsort((all_label, all_piece))
    # the sorted nodes' polygons gathered from the set's and the new ones in one pass
    # (index >= s.polygons.n: a new polygon)
    source = np.concatenate([kept, s.polygons.n + np.arange(polys.n)])[order]
    counts = np.concatenate([s.polygons.counts, polys.counts])
    twin = _twins(all_piece[order], all_label[order], source, s.polygons.n, counts)
    if twin.any():
        order, source = order[~twin], source[~twin]
    merged = ConvexPolygons._make(
        *_k.take_polygons(s.polygons.xy, s.polygons.offsets, polys.xy, polys.offsets, source)
    )
    return evolve(s, piece=all_piece[order], label_s=all_label[order], polygons=merged)


def _twins(piece, label, source, n_old: int, counts) -> NDArray[np.bool_]:
    """Which of the sorted nodes ``(piece, label)`` to drop: of two neighbours of one
    piece within ``DUPLICATE_REL`` of each other that both hold states, the new one
    (``source >= n_old``; the second if both are; ``counts[source]``: vertices). Their
    slices are one slice up to rounding, and a secant through them carries only the
    rounding: two live nodes 4e-15 s apart let the truth out of the end cell beside
    them, extrapolated over 4e-5 s. (A node without states has no value to extrapolate
    from: it stays.)"""
    drop = np.zeros(len(label), dtype=bool)
    near = (piece[1:] == piece[:-1]) & (
        np.abs(np.diff(label)) <= DUPLICATE_REL * np.maximum(np.abs(label[1:]), 1.0)
    )
    if not near.any():  # every merge asks; a pair is rare
        return drop
    new, held = source >= n_old, counts[source] > 0
    near &= held[1:] & held[:-1] & (new[1:] | new[:-1])
    for i in np.flatnonzero(near).tolist():
        if not drop[i]:  # (a chain of twins keeps every other one at least)
            drop[i + 1 if new[i + 1] else i] = True
    return drop


def _split_at(s: NodeSet, p: int, j: int) -> NodeSet:
    """Piece ``p`` split at node ``j``: labels above go to a new piece (a copy of
    ``p``'s band, log columns and upper hard limit), node ``j`` to both."""
    new = len(s.u_lo)
    cut = float(s.label_s[j])
    # nodes are sorted by piece, then label: piece p's nodes above the cut are one run
    # [c, b), and the new piece (the last index) takes node j and that run at the end
    idx = np.flatnonzero(s.piece == p)
    b = int(idx[-1]) + 1
    c = int(idx[0]) + int(np.searchsorted(s.label_s[idx], cut, side="right"))
    n = len(s.piece)
    order = np.concatenate([np.arange(c), np.arange(b, n), [j], np.arange(c, b)])
    n_new = 1 + b - c
    piece = np.concatenate([s.piece[:c], s.piece[b:], np.full(n_new, new, dtype=np.int64)])
    hard_hi = s.hard_hi_s.copy()
    hard_hi[p] = cut
    return evolve(
        s, piece=piece, label_s=s.label_s[order], polygons=s.polygons.select(order),
        u_lo=np.append(s.u_lo, s.u_lo[p]), u_hi=np.append(s.u_hi, s.u_hi[p]),
        hard_lo_s=np.append(s.hard_lo_s, cut), hard_hi_s=np.append(hard_hi, s.hard_hi_s[p]),
        log=s.log.with_copied_column(p),
    )  # fmt: skip
