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

from dataclasses import replace

import numpy as np
from kalman_vs_infoset.estim.intercept.nodeset.belief import NodeSet
from kalman_vs_infoset.estim.intercept.nodeset.refine import _compact, _merge

#: bands narrower than this (relative width in ``u``) are not split
MIN_BAND_REL = 1e-6


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


def split_live_bands(est, s: NodeSet, min_live: int, max_bands: int, rtol: float) -> NodeSet:
    """Split live bands in halves (:func:`_loosest_band` chooses) while fewer than
    ``max_bands`` are live and a split is sound; ``est`` is the
    :class:`~.estimator.NodeSetEstimator` (its ``_apply``,
    ``_prior`` and refinement)."""
    if s.is_empty or not np.any(s.u_hi - s.u_lo > MIN_BAND_REL * s.u_hi):
        return s  # a known closing speed (or bands already at their finest)
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
        two = replace(
            s, u_lo=np.r_[s.u_lo, um], u_hi=np.r_[np.where(np.arange(q) == p, um, s.u_hi), ub],
            hard_lo_s=hard_lo, hard_hi_s=hard_hi, log=s.log.with_copied_column(int(p)),
        )  # fmt: skip
        piece = np.r_[np.full(len(labels), p), np.full(len(labels), q)]
        both = np.r_[labels, labels]
        polys, _, h_lo, h_hi, _ = est._apply(
            two, piece, both, est._prior(two, piece, both), two.log, 0.0
        )
        two = replace(two, hard_lo_s=np.maximum(two.hard_lo_s, h_lo),
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
    # cells between its nodes as short as the parent's were
    for half in np.unique(s.piece[s.live & (s.u_lo >= ua)[s.piece] & (s.u_hi <= ub)[s.piece]]):
        lo, hi = est._bracket(s, int(half))
        lo, hi = max(lo, float(s.hard_lo_s[half])), min(hi, float(s.hard_hi_s[half]))
        mine = s.live & (s.piece == half)
        labels = np.unique(np.r_[np.linspace(lo, hi, est.n_nodes), s.label_s[mine]])
        s = est._regrid(s, int(half), labels)
    return _compact(s)


__all__ = ["MIN_BAND_REL", "live_bands", "split_live_bands"]
