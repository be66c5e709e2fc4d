"""Closing-speed bands of the node set that split as the data pin the speed.

A band ``[u_lo, u_hi]`` of ``u = 1/e`` keeps, at each node, the slice over *every*
``u`` of the band: the zero-effort miss ``w = zs / (u e_nom)^2`` is then bounded
over the whole band, a relaxation of ``2 |w| (u_hi - u_lo) / u`` -- small while the
set's interval of ``w`` is wide, but with a range finder the bearings and ranges
pin ``w`` to tens of metres while ``|w|`` may be kilometres (without guidance), and
the same ranges empty all but one band. :func:`split_live_bands` then splits the
live bands in halves until there are as many live bands as the estimator started
with, each half's slices recomputed exactly (the prior, then every recorded
operation, with the half's ``u`` interval; the disturbance and impulse intervals of
the parent band, recorded per piece, contain the half's).

A half is dropped only when its hard label limits (the prior box and the recorded
range intervals, for the half's ``u``) exclude the whole bracket of the parent's
live nodes: a half with no live node but states left between two nodes cannot be
told from an empty one, and then the band is not split (sound either way).
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.intercept.nodeset.belief import NodeSet, evolve
from kalman_vs_infoset.estim.intercept.nodeset.refine import _compact, _merge
from numpy.typing import NDArray

#: bands narrower than this (relative width in ``u``) are not split
MIN_BAND_REL = 1e-6
FloatArray = NDArray[np.float64]
#: a band's trial split is kept when it narrows the band's extreme nodes by this
#: times ``rtol`` of the set's width (:func:`_impulse_splits`)
GAIN = 0.5
#: seconds (of the set's time) between trial splits that did not pay
RETRY_S = 5.0
#: candidate bands tried at the nodes in one round
TRIALS = 2
#: at a range update within ``RETRY_S`` of a trial that did not pay, the extremes are
#: tried again only when the set's interval of the miss is this much narrower
NARROWED = 0.7
#: the values of ``band_trials`` (the estimator's docstring)
BAND_TRIALS = ("auto", "impulse_spread", "extreme_bands")


def live_bands(s: NodeSet) -> list[tuple[float, float]]:
    """The distinct ``(u_lo, u_hi)`` of the pieces that have live nodes."""
    lo, hi = s.u_lo.tolist(), s.u_hi.tolist()  # Python floats, as float(s.u_lo[p])
    return sorted({(lo[p], hi[p]) for p in np.unique(s.piece[s.live]).tolist()})


def _loosest_band(
    s: NodeSet, bands: list[tuple[float, float]], rtol: float, min_live: int
) -> tuple[float, float] | None:
    """The live band of ``bands`` (:func:`live_bands`) to split next, or None.

    While fewer than ``min_live`` bands are live, the widest. Otherwise one of the
    (at most two) bands whose cells attain the set's extremes of ``w``, if its
    relaxation of them, about ``2 |w| (u_hi - u_lo) / u_hi``, exceeds ``rtol`` of the
    set's width: the splits go where the interval's ends are decided, as the
    tightening's new nodes do (a band elsewhere gains nothing from a split but
    cells between fewer nodes)."""
    if len(bands) < min_live:
        wide = max(bands, key=lambda b: (b[1] - b[0]) / b[1])
        return wide if (wide[1] - wide[0]) > MIN_BAND_REL * wide[1] else None
    summ = s._summary
    w, cell_piece = summ["w"], summ["piece"]
    if len(w) == 0:
        return None
    width = float(np.nanmax(w[:, 1]) - np.nanmin(w[:, 0]))
    # each cell's band (-1: a piece whose band has no live node), then each band's
    # largest |w| over its cells in one pass (NaN ignored, -inf for a band without a
    # cell): one vector operation instead of a mask over every cell for each band
    where = {b: i for i, b in enumerate(bands)}
    lo, hi = s.u_lo.tolist(), s.u_hi.tolist()
    piece_band = np.array([where.get((a, b), -1) for a, b in zip(lo, hi, strict=True)])
    cell_band = piece_band[cell_piece]
    has = cell_band >= 0
    w_max = np.full(len(bands), -np.inf)
    np.fmax.at(w_max, cell_band[has], np.fmax(np.abs(w[has, 0]), np.abs(w[has, 1])))
    ua, ub = np.array(bands).T
    rel = (ub - ua) / ub
    loss = 2.0 * w_max * rel
    # the first band of the largest loss among those over the threshold (and over 0)
    ok = (rel > MIN_BAND_REL) & (loss > rtol * width) & (loss > 0.0)
    if not ok.any():
        return None
    i = int(np.argmax(np.where(ok, loss, -np.inf)))
    return bands[i]


def split_live_bands(
    est, s: NodeSet, min_live: int, max_bands: int, rtol: float, trials: str = "impulse_spread"
) -> NodeSet:
    """Split live bands in halves (:func:`_loosest_band` chooses) while fewer than
    ``max_bands`` are live and a split is sound, then the impulses' trial splits
    (:func:`_impulse_splits`) and, with ``trials="extreme_bands"`` (on their clock) or
    ``"at_range"`` (now, without the clock: the estimator's ``"auto"`` at a range
    update, ``"impulse_spread"`` at a bearing), the trials at the set's extremes
    (:func:`_extreme_trials`); ``est`` is the :class:`~.estimator.NodeSetEstimator`
    (its ``_apply``, ``_prior`` and refinement)."""
    if s.is_empty or not np.any(s.u_hi - s.u_lo > MIN_BAND_REL * s.u_hi):
        return s  # a known closing speed (or bands already at their finest)
    min_live = max(min_live, s.live_band_target)
    s = _split_loosest(est, s, min_live, max_bands, rtol)
    s = _impulse_splits(est, s, max_bands, rtol)
    if trials in ("extreme_bands", "at_range"):  # then the bands at the set's extremes
        return _extreme_trials(est, s, min_live, max_bands, rtol, trials == "extreme_bands")
    return s


def _split_loosest(est, s: NodeSet, min_live: int, max_bands: int, rtol: float) -> NodeSet:
    """Split the band :func:`_loosest_band` names while one is named, fewer than
    ``max_bands`` are live and a split is sound."""
    for _ in range(2 * max_bands):
        bands = live_bands(s)
        if len(bands) >= max_bands:
            break
        band = _loosest_band(s, bands, rtol, min_live)
        if band is None:
            break
        out = _split_band(est, s, *band)
        if out is None or out.is_empty:
            break
        s = out
    return s


def _band_extremes(s: NodeSet, bands: list[tuple[float, float]]) -> tuple[FloatArray, FloatArray]:
    """Bounds of ``w`` over each band's cells (``inf, -inf`` for a band without one)."""
    summ = s._summary
    where = {b: i for i, b in enumerate(bands)}
    lo, hi = s.u_lo.tolist(), s.u_hi.tolist()
    cell_band = np.array([where.get((a, b), -1) for a, b in zip(lo, hi, strict=True)])[
        summ["piece"]
    ]
    has = cell_band >= 0
    w_lo, w_hi = np.full(len(bands), np.inf), np.full(len(bands), -np.inf)
    np.fmin.at(w_lo, cell_band[has], summ["w"][has, 0])
    np.fmax.at(w_hi, cell_band[has], summ["w"][has, 1])
    return w_lo, w_hi


def _w_at_nodes(polys, u_lo: FloatArray, u_hi: FloatArray, e_nom: float) -> FloatArray:
    """Bounds (n, 2) of ``w = zs / (u e_nom)^2`` over each node's slice and ``u`` in
    ``[u_lo, u_hi]`` (NaN for an empty slice)."""
    off = polys.offsets
    out = np.full((polys.n, 2), np.nan)
    for i in range(polys.n):
        if off[i + 1] > off[i]:
            zs = polys.xy[off[i] : off[i + 1], 1]
            f_near, f_far = (1.0 / (u_lo[i] * e_nom)) ** 2, (1.0 / (u_hi[i] * e_nom)) ** 2
            lo, hi = zs.min(), zs.max()
            out[i] = (lo * (f_near if lo < 0 else f_far), hi * (f_near if hi > 0 else f_far))
    return out


def _node_gain(est, s: NodeSet, ua: float, ub: float) -> float:
    """What splitting band ``[ua, ub]`` narrows its interval of ``w`` by, estimated at
    the nodes of the cells that attain the band's extremes (their slices replayed
    for both halves: a few nodes, not the band's whole grid)."""
    summ = s._summary
    cells = np.flatnonzero(((s.u_lo == ua) & (s.u_hi == ub))[summ["piece"]])
    if len(cells) == 0:
        return 0.0
    w = summ["w"][cells]
    # the end nodes of the cells that attain the band's extremes; of each pair, the
    # node whose exact slice reaches further that way (one replayed node an end)
    picked: list[int] = []
    for c, col in ((cells[np.nanargmin(w[:, 0])], 0), (cells[np.nanargmax(w[:, 1])], 1)):
        pair = summ["table"][c, 1:3]
        pair = pair[pair >= 0]
        pair = pair[s.live[pair]]
        if len(pair):
            at = _w_at_nodes(s.polygons.select(pair), s.u_lo[s.piece[pair]],
                             s.u_hi[s.piece[pair]], s.e_nom)[:, col]  # fmt: skip
            picked.append(int(pair[np.argmin(at) if col == 0 else np.argmax(at)]))
    if not picked:
        return 0.0
    nodes = np.unique(picked)
    piece, labels = s.piece[nodes], s.label_s[nodes]
    before = _w_at_nodes(s.polygons.select(nodes), s.u_lo[piece], s.u_hi[piece], s.e_nom)
    um = 0.5 * (ua + ub)
    # every involved piece's halves as pieces of their own: [ua, um] and [um, ub]
    pcs = np.unique(piece)
    n0 = len(s.u_lo)
    log = s.log
    for p in pcs:
        log = log.with_copied_column(int(p))
    for p in pcs:
        log = log.with_copied_column(int(p))
    halves = evolve(
        s, u_lo=np.r_[s.u_lo, np.full(len(pcs), ua), np.full(len(pcs), um)],
        u_hi=np.r_[s.u_hi, np.full(len(pcs), um), np.full(len(pcs), ub)],
        hard_lo_s=np.r_[s.hard_lo_s, s.hard_lo_s[pcs], s.hard_lo_s[pcs]],
        hard_hi_s=np.r_[s.hard_hi_s, s.hard_hi_s[pcs], s.hard_hi_s[pcs]], log=log,
    )  # fmt: skip
    where = n0 + np.searchsorted(pcs, piece)
    hp = np.r_[where, where + len(pcs)]
    hl = np.r_[labels, labels]
    polys = est._apply(halves, hp, hl, est._prior(halves, hp, hl), log, 0.0)[0]
    after = _w_at_nodes(polys, halves.u_lo[hp], halves.u_hi[hp], s.e_nom)
    k = len(nodes)
    lo_after = np.fmin(after[:k, 0], after[k:, 0])
    hi_after = np.fmax(after[:k, 1], after[k:, 1])
    gain_lo = np.nanmin(lo_after) - np.nanmin(before[:, 0]) if np.isfinite(lo_after).any() else 0.0
    gain_hi = np.nanmax(before[:, 1]) - np.nanmax(hi_after) if np.isfinite(hi_after).any() else 0.0
    return float(max(gain_lo, 0.0) + max(gain_hi, 0.0))


def _impulse_splits(est, s: NodeSet, max_bands: int, rtol: float) -> NodeSet:
    """Split the bands whose spread of the impulses may widen ``w`` by more than
    ``rtol`` of the set's width, where a trial shows that it does.

    A band applies each impulse ``k`` for every ``u`` of the band, as if ``u`` could
    change between impulses: that widens ``w`` by up to about ``|k| tau du / u`` an
    impulse (:attr:`NodeSet.impulse_moment_m` times the band's relative width),
    which :func:`_loosest_band`'s ``2 |w| du / u`` does not count. Later bearings cut
    most of that spread again, so the bound overstates it late in the approach and
    only selects candidates. The ``TRIALS`` candidates of the widest ``u`` intervals
    (then of ``w``) are tried at the nodes of their extreme cells
    (:func:`_node_gain`), and the best is split when
    the halves narrow them by at least ``GAIN * rtol`` of the set's width (a split
    takes about half the spread). A trial that does not pay waits ``RETRY_S``
    seconds: a few cheap trials an engagement.
    """
    m = s.impulse_moment_m
    if m == 0.0 or s.t_s < s.band_trial_after_s or s.is_empty:
        return s
    # no candidate when even the widest piece's spread is under rtol of the width (the
    # per-piece summary: one vector test an update before any per-band work)
    per = s._summary["per_piece"]
    rel_max = float(np.max((s.u_hi - s.u_lo) / s.u_hi))
    if not rel_max * m > rtol * (np.nanmax(per[:, 1]) - np.nanmin(per[:, 0])):
        return s
    while not s.is_empty:
        bands = live_bands(s)
        if len(bands) >= max_bands:
            break
        w_lo, w_hi = _band_extremes(s, bands)
        width = float(w_hi.max() - w_lo.min())
        ua, ub = np.array(bands).T
        rel = (ub - ua) / ub
        ok = (rel > MIN_BAND_REL) & (rel * m > rtol * width) & (w_hi >= w_lo)
        if not ok.any():
            break
        # the widest bands in u first (the largest spread), the widest in w among them
        order = np.lexsort((-(w_hi - w_lo), -rel))
        tried = [int(i) for i in order if ok[i]][:TRIALS]
        gains = [_node_gain(est, s, *bands[i]) for i in tried]
        j = int(np.argmax(gains))
        if gains[j] >= GAIN * rtol * width:
            out = _split_band(est, s, *bands[tried[j]])
            if out is not None and not out.is_empty:
                s = out
                continue
        s = evolve(s, band_trial_after_s=s.t_s + RETRY_S)
        break
    return s


def _extreme_trials(
    est, s: NodeSet, min_live: int, max_bands: int, rtol: float, clock: bool = True
) -> NodeSet:
    """Halve every live band when a trial at the set's extremes shows that it pays
    (after :func:`_impulse_splits`, whose candidates are tried first, as by default).

    A band relaxes more than the miss's own ``2 |w| du / u``: its ``u`` spread scales
    the prior box, the disturbance and the impulses too, and with a range finder
    (which pins ``u``, so the set's interval of ``w`` is narrow) the sum reached about
    three times that bound, in every band alike (docs/infoset.md). So, impulses or
    not, the (at most two) bands that attain the set's extremes of ``w`` are tried
    (:func:`_node_gain`); when one narrows its extreme nodes by ``GAIN * rtol`` of the
    set's width, the live-band target doubles (up to ``max_bands``) and
    :func:`_loosest_band` halves the widest bands up to it: halving only the extreme
    band would leave its neighbours, relaxed alike, at nearly the same extreme. A
    trial that does not pay waits ``RETRY_S`` seconds, on a clock of its own
    (``extreme_trial_after_s``): the impulses' trials keep their schedule. Without
    ``clock`` (``band_trials="auto"``, called at range updates only) the trials run
    every call.
    """
    # a clock of their own: the impulses' trials neither delay these nor are delayed
    if s.is_empty or (clock and s.t_s < s.extreme_trial_after_s):
        return s
    bands = live_bands(s)
    if len(bands) >= max_bands:
        return s
    w_lo, w_hi = _band_extremes(s, bands)
    width = float(w_hi.max() - w_lo.min())
    if not clock and s.t_s < s.extreme_trial_after_s and width > NARROWED * s.extreme_trial_width_m:
        return s  # at a range: within RETRY_S of a trial that did not pay, and no narrower
    ua, ub = np.array(bands).T
    ok = ((ub - ua) > MIN_BAND_REL * ub) & (w_hi >= w_lo)
    tried = sorted({int(np.argmin(w_lo)), int(np.argmax(w_hi))})
    gains = [_node_gain(est, s, *bands[i]) for i in tried if ok[i]]
    if gains and max(gains) >= GAIN * rtol * width:
        target = min(max_bands, 2 * max(len(bands), min_live))
        out = _split_loosest(est, s, target, max_bands, rtol)
        reached = len(live_bands(out))
        if reached >= target:
            return evolve(out, live_band_target=target)
        # a target the splits could not reach (a half that cannot be told from empty) is
        # not kept, and the trials wait: else every update would replay those splits
        return evolve(
            out, live_band_target=reached, extreme_trial_after_s=s.t_s + RETRY_S,
            extreme_trial_width_m=width,
        )  # fmt: skip
    return evolve(s, extreme_trial_after_s=s.t_s + RETRY_S, extreme_trial_width_m=width)


def _split_band(est, s: NodeSet, ua: float, ub: float) -> NodeSet | None:
    """Every piece of band ``[ua, ub]`` split at ``u``'s middle (None: not sound)."""
    um = 0.5 * (ua + ub)
    (_, _), (_, _), (xa, xb) = s.prior
    for p in np.flatnonzero((s.u_lo == ua) & (s.u_hi == ub)):
        idx = np.flatnonzero(s.piece == p)
        if not s.live[idx].any():
            continue
        labels = s.label_s[idx]
        q = len(s.u_lo)
        # the lower half keeps index p, the upper one is the new piece q; both start
        # from the parent's hard limits cut to their own u by the prior box
        hard_lo = np.r_[s.hard_lo_s, max(s.hard_lo_s[p], xa * um)]
        hard_hi = np.r_[s.hard_hi_s, s.hard_hi_s[p]]
        hard_hi[p] = min(hard_hi[p], xb * um)
        two = evolve(
            s, u_lo=np.r_[s.u_lo, um], u_hi=np.r_[np.where(np.arange(q) == p, um, s.u_hi), ub],
            hard_lo_s=hard_lo, hard_hi_s=hard_hi, log=s.log.with_copied_column(int(p)),
        )  # fmt: skip
        piece = np.r_[np.full(len(labels), p), np.full(len(labels), q)]
        both = np.r_[labels, labels]
        polys, _, h_lo, h_hi, _ = est._apply(
            two, piece, both, est._prior(two, piece, both), two.log, 0.0
        )
        two = evolve(two, hard_lo_s=np.maximum(two.hard_lo_s, h_lo),
                      hard_hi_s=np.minimum(two.hard_hi_s, h_hi))  # fmt: skip
        counts = polys.counts
        # the parent's feasible labels: between its dead end nodes, or out to its
        # hard limits where an end node is live
        live = s.live[idx]
        bracket = (
            float(labels[0] if not live[0] else s.hard_lo_s[p]),
            float(labels[-1] if not live[-1] else s.hard_hi_s[p]),
        )
        for half, rows in ((p, slice(0, len(labels))), (q, slice(len(labels), None))):
            if (counts[rows] > 0).any():
                continue
            # no live node: sound to drop only if the hard limits exclude the bracket
            if not (two.hard_lo_s[half] > bracket[1] or two.hard_hi_s[half] < bracket[0]):
                return None
        s = _merge(two, two.piece != p, piece, both, polys)
    s = _compact(est._refine_pieces(s))
    # each half's feasible labels are narrower than its parent's: a fresh grid of
    # n_nodes over its bracket (its live labels kept, so none is lost) keeps the
    # cells between its nodes as short as the parent's were. The live nodes keep their
    # slices: they were replayed above with this log and this band, and the hard limits
    # raised since then only empty nodes that are not live (so a replay again would
    # give the same polygons); only the grid's other labels are replayed.
    for half in np.unique(s.piece[s.live & (s.u_lo >= ua)[s.piece] & (s.u_hi <= ub)[s.piece]]):
        lo, hi = est._bracket(s, int(half))
        lo, hi = max(lo, float(s.hard_lo_s[half])), min(hi, float(s.hard_hi_s[half]))
        s = est._regrid_keeping_live(s, int(half), np.linspace(lo, hi, est.n_nodes))
    return _compact(s)


__all__ = ["MIN_BAND_REL", "live_bands", "split_live_bands"]
