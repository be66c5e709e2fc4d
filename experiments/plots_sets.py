"""Pictures of an information set from a trace's sets file (:mod:`experiments.traces`).

The set of one channel is a stack of sections (polygons) in (bearing ``alpha``,
zero-effort miss ``w = omega x^2 / e``), each at its range ``x``:

* :func:`stacked_3d`: the sections stacked along the range in 3-D, like the seed's
  Fig. 4 -- (a) before the step's measurements, (b) after them, the part that remains
  shaded and the part cut away as outlines;
* :func:`slices`: 2-D pictures at chosen times, every section's polygon projected onto
  (bearing, zero-effort miss), the truth marked;
* :func:`animate`: the same projection over the whole engagement as a GIF (matplotlib's
  pillow writer).

Colour = estimator (:mod:`kalman_vs_infoset.experiments.figstyle`); the truth is black.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments.files import atomic_write
from matplotlib import animation
from matplotlib.collections import PolyCollection
from mpl_toolkits.mplot3d.art3d import Poly3DCollection


def _sections(d: pd.DataFrame, closing_speed_mps: float | None = None):
    """``(x_km, alpha_mrad, w_km)`` vertex arrays of each section of one snapshot; with
    ``closing_speed_mps`` (``e``) the third is the line-of-sight rate ``omega = w e / x^2``
    in microradians per second (the seed's coordinates ``(alpha, omega, x)``; linear in
    ``w`` on each section, so a polygon maps to a polygon)."""
    for _, s in d.sort_values(["section", "vertex"]).groupby("section", sort=True):
        x_m, w_m = s["x_m"].to_numpy(), s["zem_m"].to_numpy()
        third = w_m / 1e3 if closing_speed_mps is None else w_m * closing_speed_mps / x_m**2 * 1e6
        yield x_m / 1e3, s["alpha_rad"].to_numpy() * 1e3, third


def run_words(df: pd.DataFrame, run: int) -> str:
    """Which run a trace's rows ``df`` are, in words for a title: the estimator and the
    noise (:func:`~kalman_vs_infoset.experiments.figstyle.words`), the seed when the
    rows carry it, and the run: ``"information set, random errors, seed 5, run 0"``."""
    est = str(df["estimator"].iloc[0])
    noise = str(df["noise"].iloc[0]) if "noise" in df else None
    seed = df["seed"].iloc[0] if "seed" in df else None
    at = "" if seed is None or pd.isna(seed) else f", seed {int(seed)}"
    return f"{fs.words(est, noise)}{at}, run {run}"


def _snapshot(sets: pd.DataFrame, run: int, step: int, phase: str, channel=None):
    d = sets[(sets["run"] == run) & (sets["step"] == step) & (sets["phase"] == phase)]
    if channel is not None:
        d = d[d["channel"] == channel]
    return d


def _truth(steps: pd.DataFrame | None, run: int, step: int, channel=None, closing_speed_mps=None):
    if steps is None:
        return None
    d = steps[(steps["run"] == run) & (steps["step"] == step)]
    if channel is not None:
        d = d[d["channel"] == channel]
    if not len(d):
        return None
    r = d.iloc[0]
    third = r["zem_true_m"] / 1e3
    if closing_speed_mps is not None:
        third = r["zem_true_m"] * closing_speed_mps / r["x_true_m"] ** 2 * 1e6
    return r["x_true_m"] / 1e3, r["alpha_true_rad"] * 1e3, third


def _equal_length(polys: list) -> np.ndarray:
    """The polygons as one ``(n, max vertices, 3)`` array, each padded by repeating its
    last vertex (a zero-length edge: the same closed outline).

    Poly3DCollection pads a ragged list itself with uninitialised memory, which it
    marks invalid but still projects: whatever the memory held can overflow the
    projection's dot product (a RuntimeWarning that came and went with the state of
    the process; matplotlib issue #32272). An equal-length array has no padding."""
    n_max = max(len(p) for p in polys)
    out = np.empty((len(polys), n_max, 3))
    for i, p in enumerate(polys):
        out[i, : len(p)] = p
        out[i, len(p) :] = p[-1]
    return out


def _draw_3d(ax, polys: list, colour: str, shaded: bool, label: str) -> None:
    if not polys:
        return
    coll = Poly3DCollection(
        _equal_length(polys),
        facecolor=colour if shaded else "none",
        edgecolor=colour,
        alpha=0.45 if shaded else 0.9,
        linewidths=0.8,
        linestyles="-" if shaded else ":",
        label=label,
    )
    ax.add_collection3d(coll)
    ax.plot([], [], color=colour, ls="-" if shaded else ":", label=label)  # legend handle


def _limits_3d(ax, polys: list) -> None:
    """Axis limits holding every drawn section (the set before the measurements too)."""
    allv = np.vstack(polys)
    for setter, k in ((ax.set_xlim, 0), (ax.set_ylim, 1), (ax.set_zlim, 2)):
        lo, hi = allv[:, k].min(), allv[:, k].max()
        # a flat extent (a point range, say) still gets a width the projection can
        # resolve: relative to the coordinate's size, not an absolute 1e-9
        pad = 0.05 * (hi - lo) + 1e-6 * max(abs(lo), abs(hi), 1.0)
        setter(lo - pad, hi + pad)


def _labels_3d(ax, rate: bool = False) -> None:
    ax.set_xlabel("range x, km")
    ax.set_ylabel("bearing alpha, mrad")
    ax.set_zlabel("line-of-sight rate omega, µrad/s" if rate else "zero-effort miss w, km")


def stacked_3d(
    sets: pd.DataFrame,
    run: int,
    step: int,
    steps=None,
    channel=None,
    title="",
    closing_speed_mps: float | None = None,
):
    """(a) the set before the step's measurements, (b) after (remaining part shaded).

    With ``closing_speed_mps`` (``e``) a second row draws the same sets in the seed's
    coordinates ``(alpha, omega, x)`` above the miss-coordinate view ``(alpha, w, x)``.
    Both panels of a row share the limits of the set before the measurements.
    """
    fs.setup()
    views = [None] if closing_speed_mps is None else [closing_speed_mps, None]
    fig = fs.plt.figure(figsize=(11.0, 5.0 * len(views)), constrained_layout=True)
    est = str(sets["estimator"].iloc[0])
    colour = fs.estimator_colour(est)
    prior = _snapshot(sets, run, step, "prior", channel)
    post = _snapshot(sets, run, step, "posterior", channel)
    t = float(post["t_s"].iloc[0]) if len(post) else float("nan")
    letters = iter("abcd")
    for row, e in enumerate(views):
        before = [np.column_stack(v) for v in _sections(prior, e)]
        after = [np.column_stack(v) for v in _sections(post, e)]
        truth = _truth(steps, run, step, channel, e)
        where = "seed's coordinates" if e is not None else "miss coordinate"
        for col, parts in enumerate(
            (
                [(before, False, "set before the measurements")],
                [
                    (before, False, "set before the measurements"),
                    (after, True, "part that remains"),
                ],
            )
        ):
            ax = fig.add_subplot(len(views), 2, 2 * row + col + 1, projection="3d")
            for polys, shaded, label in parts:
                _draw_3d(ax, polys, colour, shaded, f"{fs.words(est)}: {label}")
            if before or after:
                _limits_3d(ax, before + after)
            if truth is not None:  # drawn last and on top: not hidden behind a surface
                ax.computed_zorder = False
                ax.plot(*[[v] for v in truth], "o", color=fs.TRUTH, ms=5, label="truth",
                        zorder=10)  # fmt: skip
            _labels_3d(ax, e is not None)
            when = "before" if col == 0 else "after"
            ax.set_title(
                f"({next(letters)}) {when} the measurements, t = {t:g} s ({where})", fontsize=9
            )
            ax.view_init(elev=18, azim=-58)
            fs.legend(ax, loc="upper left")
    if title:
        fig.suptitle(title)
    return fig


def slices(sets: pd.DataFrame, run: int, steps_df=None, times=None, channel=None, n=6):
    """2-D pictures of the set after the measurements at ``n`` times (or ``times``, s)."""
    post = sets[(sets["run"] == run) & (sets["phase"] == "posterior")]
    if channel is not None:
        post = post[post["channel"] == channel]
    avail = np.array(sorted(post["step"].unique()))
    if times is None:
        chosen = avail[np.unique(np.linspace(0, len(avail) - 1, min(n, len(avail))).astype(int))]
    else:
        t_of = post.groupby("step")["t_s"].first()
        chosen = [int(t_of.index[np.argmin(np.abs(t_of.to_numpy() - t))]) for t in times]
    ncols = min(3, len(chosen))
    nrows = int(np.ceil(len(chosen) / ncols))
    fig, axes = fs.figure(nrows, ncols, size=(4.0 * ncols, 3.4 * nrows))
    est = str(sets["estimator"].iloc[0])
    colour = fs.estimator_colour(est)
    for ax, step in zip(axes.flat, chosen, strict=False):
        d = post[post["step"] == step]
        _draw_2d(ax, d, colour, est)
        tr = _truth(steps_df, run, int(step), channel)
        if tr is not None:  # above the sections' fill
            ax.plot([tr[1]], [tr[2] * 1e3], "o", color=fs.TRUTH, ms=4, label="truth", zorder=5)
        ax.set_title(f"t = {float(d['t_s'].iloc[0]):g} s, {d['section'].nunique()} sections")
    for ax in axes.flat[len(chosen) :]:
        ax.set_visible(False)
    # one legend below the panels: early sets fill their whole panel, where a legend
    # inside would hide the truth
    fs.figure_legend(fig, axes.flat[: len(chosen)], fontsize=8)
    fig.suptitle(
        f"{sets['scenario'].iloc[0]}: the set projected on (bearing, miss), {run_words(sets, run)}"
    )
    return fig


def _draw_2d(ax, d: pd.DataFrame, colour: str, est: str) -> None:
    """Every section of a snapshot as one collection (filled faintly, edges drawn)."""
    polys = [np.column_stack([a, w * 1e3]) for _, a, w in _sections(d)]
    coll = PolyCollection(
        polys,
        facecolors=colour,
        edgecolors=colour,
        alpha=0.35,
        linewidths=0.7,
        label=f"{fs.words(est)}: sections at their ranges",
    )
    ax.add_collection(coll)
    ax.autoscale_view()
    ax.set_xlabel("bearing alpha, mrad")
    ax.set_ylabel("zero-effort miss w, m")


def animate(
    sets: pd.DataFrame,
    run: int,
    path: Path,
    steps_df=None,
    channel=None,
    fps=3,
    max_frames: int = 12,
):
    """A GIF of the set after the measurements over the engagement (pillow writer), at
    most ``max_frames`` recorded steps evenly spread."""
    post = sets[(sets["run"] == run) & (sets["phase"] == "posterior")]
    if channel is not None:
        post = post[post["channel"] == channel]
    frames = sorted(post["step"].unique())
    pick = np.unique(np.linspace(0, len(frames) - 1, min(max_frames, len(frames))).astype(int))
    frames = [frames[i] for i in pick]
    est = str(sets["estimator"].iloc[0])
    colour = fs.estimator_colour(est)
    fs.setup()
    fig = fs.plt.figure(figsize=(5.6, 4.2))  # fixed layout: re-laid out per frame is slow
    ax = fig.add_axes((0.16, 0.13, 0.8, 0.78))

    def draw(step):
        ax.clear()
        d = post[post["step"] == step]
        _draw_2d(ax, d, colour, est)
        tr = _truth(steps_df, run, int(step), channel)
        if tr is not None:
            ax.plot([tr[1]], [tr[2] * 1e3], "o", color=fs.TRUTH, ms=4, label="truth")
        ax.set_title(f"{fs.words(est)}, run {run}: t = {float(d['t_s'].iloc[0]):g} s")
        fs.legend(ax, loc="upper right")
        return ()

    anim = animation.FuncAnimation(fig, draw, frames=frames, blit=False)
    # written whole or not at all, as every other file (atomic_write): pillow takes the
    # format from the name, so the frames go to a GIF of their own first
    with tempfile.TemporaryDirectory() as scratch:
        gif = Path(scratch) / "set.gif"
        anim.save(gif, writer=animation.PillowWriter(fps=fps), dpi=72)
        atomic_write(path, lambda tmp: shutil.copyfile(gif, tmp))
    fs.plt.close(fig)
    return path
