"""One figure style for every figure of the package (matplotlib, Agg backend).

What encodes what, the same way in every figure:

* **colour = estimator**, declared by each estimator's registration
  (:mod:`kalman_vs_infoset.estim.registry`; Okabe-Ito palette, safe for the common
  colour-vision deficiencies, for the package's first estimators: the information set
  blue, the box sky blue, EKF vermillion, UKF bluish green, the perfect-information
  point reddish purple; the other families darker hues: ellipsoid orange, zonotope
  brown, H-infinity wine, particle filter indigo), so a figure with all eight intercept
  estimators has eight colours; an estimator registered without a colour takes a spare
  one by name (stable across figures and runs);
* **line style = noise**: random solid, game dashed, bias dotted, none dash-dotted,
  the white-box adversaries (targeted, lookahead) and switching errors dash-dot
  patterns of their own;
* **black = the truth**, grey = measurements and our own reference marks (lower
  bounds, limits); the paper's printed numbers are black star markers or black
  dotted lines labelled "paper: ...";
* every axis label names its unit after a comma (``"miss, m"``; dimensionless
  quantities say ``"-"``), every drawn line and patch has a legend entry, and every
  figure is written as PNG and SVG (:func:`save`).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable
from functools import partial
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")  # files only; no display needed (CI, clusters)
import matplotlib.pyplot as plt  # noqa: E402
from kalman_vs_infoset.experiments.files import derived_write  # noqa: E402
from matplotlib import ticker  # noqa: E402
from matplotlib.font_manager import FontProperties  # noqa: E402

#: Okabe & Ito (2008), "Color Universal Design"
OKABE_ITO = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}
#: for estimators without a fixed colour (yellow is kept for fills only)
#: (no grey: the reference marks are grey; Tol's teal, olive, purple and dark red)
_SPARE = ("#44AA99", "#999933", "#AA4499", "#661100")
NOISE_STYLES: dict[str, str | tuple[Any, ...]] = {
    "random": "-",
    "game": "--",
    "bias": ":",
    "none": "-.",
    "targeted": (0, (6, 1.5, 1, 1.5, 1, 1.5)),
    "lookahead": (0, (2, 1, 2, 1, 6, 1)),
    "switch": (0, (10, 2)),
}
TRUTH = OKABE_ITO["black"]
MEASURED = "#8C8C8C"
REFERENCE = "#6E6E6E"
PAPER = OKABE_ITO["black"]
#: the paper's printed numbers
PAPER_MARKER = {"marker": "*", "ms": 11, "color": PAPER, "ls": "none"}
DPI = 110
SIZE_ONE = (6.4, 4.2)


def _registrations(name: str):
    from kalman_vs_infoset.estim import registry  # the registry, not the style, is heavy

    return registry.by_name(name)


def estimator_colour(name: str) -> str:
    """The colour of an estimator: its registration's, else a spare one chosen by name."""
    for reg in _registrations(name):
        if reg.colour:
            return reg.colour
    digest = hashlib.sha256(name.encode()).digest()
    return _SPARE[digest[0] % len(_SPARE)]


#: legends in words: what a noise kind is
NOISE_WORDS = {
    "random": "random errors",
    "game": "game errors",
    "bias": "biased errors",
    "none": "exact measurements",
    "targeted": "targeted adversary",
    "lookahead": "look-ahead adversary",
    "switch": "switching errors",
}


#: the intercept CDFs' marks: the miss scale the last bearings leave (a scale, not a
#: floor: runs end below it) and the mean fuel of perfect information (a lower bound)
MISS_SCALE_MARK = "bearing-limited miss scale"
PERFECT_INFO_MARK = "perfect information (mean)"


def paper_fig3(noise: str) -> str:
    """The legend of a mark at the intercept paper's Fig. 3 number under ``noise`` (one
    engagement; "seed" in a legend read as a random seed)."""
    return f"paper Fig. 3 (one engagement), {NOISE_WORDS.get(noise, noise)}"


def words(estimator: str, noise: str | None = None) -> str:
    """An estimator (and a noise kind) in words for a legend, e.g. ``"UKF, random errors"``.

    The estimator's words are its registration's label (else its name); exact
    measurements read directly (an estimator with the role ``exact``) are ``"exact state"``.
    """
    regs = _registrations(estimator)
    if noise == "none" and any("exact" in r.roles for r in regs):
        return "exact state"
    est = next((r.label for r in regs if r.label), estimator)
    return est if noise is None else f"{est}, {NOISE_WORDS.get(noise, noise)}"


def noise_style(noise: str) -> str | tuple[Any, ...]:
    """The line style of a noise kind (unknown kinds: a long dash)."""
    return NOISE_STYLES.get(noise, (0, (8, 2)))


def line(estimator: str, noise: str) -> dict:
    """Keyword arguments of a curve of ``estimator`` under ``noise``."""
    return {"color": estimator_colour(estimator), "ls": noise_style(noise), "lw": 1.5}


def setup() -> None:
    """The package's rc parameters (font sizes, grid)."""
    plt.rcParams.update(
        {
            "font.size": 9,
            "axes.titlesize": 9,
            "axes.labelsize": 9,
            "legend.fontsize": 7.5,
            "axes.grid": True,
            "grid.alpha": 0.3,
            "svg.fonttype": "none",
            "savefig.dpi": DPI,
            # tick labels say their values: an offset ("1e-6+1.068e-2") is written below
            # the axis's end, on its label, where runs differ in the sixth digit
            "axes.formatter.useoffset": False,
        }
    )


def figure(nrows: int = 1, ncols: int = 1, size=None, **kw):
    """A new figure in the package's style (``constrained_layout``)."""
    setup()
    size = size or (SIZE_ONE[0] * max(1, ncols * 0.8), SIZE_ONE[1] * max(1, nrows * 0.6))
    return plt.subplots(nrows, ncols, figsize=size, constrained_layout=True, squeeze=False, **kw)


def legend(ax, **kw) -> None:
    """A legend with one entry per distinct label (artists sharing a label share it)."""
    handles, labels = ax.get_legend_handles_labels()
    seen: dict[str, object] = {}
    for h, lab in zip(handles, labels, strict=True):
        seen.setdefault(lab, h)
    if seen:
        ax.legend(list(seen.values()), list(seen), **{"loc": "best", **kw})


def figure_legend(fig, axes: Iterable, **kw) -> None:
    """One legend for the whole figure from the labels of ``axes`` (outside, below)."""
    seen: dict[str, object] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    if not seen:
        return
    opts = {"loc": "outside lower center", "ncol": min(4, len(seen)), **kw}
    renderer = fig.canvas.get_renderer()
    # fewer columns while it is wider than the figure (long labels, four columns: cut
    # at both edges)
    for ncol in range(int(opts["ncol"]), 0, -1):
        leg = fig.legend(list(seen.values()), list(seen), **{**opts, "ncol": ncol})
        if ncol == 1 or leg.get_window_extent(renderer).width <= 0.98 * fig.bbox.width:
            return
        leg.remove()


def paper_line(ax, value: float, text: str, axis: str = "y", who: str = "paper") -> None:
    """The paper's printed number as a black dotted line labelled ``who: text`` (``who``
    says which figure's number it is when not the plotted one's)."""
    draw = ax.axhline if axis == "y" else ax.axvline
    draw(value, color=PAPER, ls=":", lw=1.2, label=f"{who}: {text}")


_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
#: matplotlib's log labels: [-][coeff \times] base [^{power}]
_MATH_LABEL = re.compile(
    r"^\$\\mathdefault\{(-?)(?:([0-9.e+-]+)\\times)?([0-9.]+)(?:\^\{(-?[0-9]+)\})?\}\$$"
)


def _plain_label(text: str) -> str:
    r"""``$\mathdefault{2\times10^{-3}}$`` as ``2×10⁻³`` (text, not mathtext); any other
    label unchanged."""
    m = _MATH_LABEL.match(text)
    if m is None:
        return text
    sign, coeff, base, power = m.groups()
    out = "\u2212" if sign else ""  # the minus sign mathtext draws
    out += "" if coeff is None else coeff + "×"
    return out + base + ("" if power is None else power.translate(_SUPERSCRIPT))


class _PlainLogFormatter(ticker.LogFormatterSciNotation):
    """The log axes' tick labels of matplotlib's default formatter, as plain text with
    Unicode superscripts: the same labels, without mathtext's parser (about 8 ms a
    label and font size, most of the time a figure with log axes took to write)."""

    def __call__(self, x, pos=None):
        return _plain_label(super().__call__(x, pos))


def plain_log_labels(fig) -> None:
    """Give every log and symlog axis of ``fig`` plain-text tick labels
    (:class:`_PlainLogFormatter`, keeping each formatter's settings)."""
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for fmt in (axis.get_major_formatter(), axis.get_minor_formatter()):
                if type(fmt) is ticker.LogFormatterSciNotation:
                    fmt.__class__ = _PlainLogFormatter  # same state, plain __call__


#: a tick label's character, as a share of its font size (DejaVu Sans digits: 0.64)
_CHAR_EM = 0.64


def thin_crowded_ticks(fig) -> None:
    """Fewer ticks on the linear x axes whose labels would run into each other.

    Without an offset (``axes.formatter.useoffset``) values that differ in the sixth
    digit are written whole (``0.0106805``), and matplotlib's default locator places
    its ticks by the axis's length, not by their labels' width: on a third of a wide
    figure eight such labels overlapped. After the layout (the axes' final widths),
    each label's width is estimated from its characters (half a character more as a
    gap); where two neighbours would meet, the same steps with fewer bins, down to
    the most ticks that keep them apart (the tick nearest the middle alone, at the
    least)."""
    fig_w_pt = fig.get_figwidth() * 72.0
    rc = FontProperties(size=plt.rcParams["xtick.labelsize"]).get_size_in_points()
    for ax in fig.axes:
        axis = ax.xaxis
        if hasattr(ax, "get_zlim") or axis.get_scale() != "linear":
            continue
        if type(axis.get_major_locator()) is not ticker.AutoLocator:
            continue  # a locator the figure chose itself
        lo, hi = sorted(ax.get_xlim())  # (autoscaled to the data drawn, if not yet)
        if not hi > lo:
            continue
        size = max((lab.get_size() for lab in axis.get_ticklabels()), default=rc)
        view = (lo, hi, ax.get_position().width * fig_w_pt, size, axis.get_major_formatter())
        if _labels_apart(axis.get_major_locator(), *view):
            continue
        n = len(_ticks_within(axis.get_major_locator(), lo, hi))
        steps = [1, 2, 2.5, 5, 10]
        thinner: ticker.Locator
        for bins in range(n - 1, 0, -1):
            thinner = ticker.MaxNLocator(nbins=bins, steps=steps, min_n_ticks=1)
            if _labels_apart(thinner, *view):
                break
        else:  # not even two labels fit
            ticks = _ticks_within(ticker.MaxNLocator(nbins=1, steps=steps), lo, hi)
            middle = min(ticks, key=lambda t: abs(t - 0.5 * (lo + hi)), default=0.5 * (lo + hi))
            thinner = ticker.FixedLocator([middle])
        axis.set_major_locator(thinner)


def _ticks_within(locator, lo: float, hi: float) -> list[float]:
    """``locator``'s ticks over ``[lo, hi]`` that lie on the axis (to rounding)."""
    slack = 1e-9 * (hi - lo)
    return [float(t) for t in locator.tick_values(lo, hi) if lo - slack <= t <= hi + slack]


def _labels_apart(locator, lo: float, hi: float, room_pt: float, size: float, fmt) -> bool:
    """Whether the labels of ``locator``'s ticks on an axis ``room_pt`` long, of font
    size ``size``, stay apart (each estimated from its characters)."""
    ticks = _ticks_within(locator, lo, hi)
    if len(ticks) < 2:
        return True
    half = np.array([(len(t) + 0.5) * _CHAR_EM * size / 2 for t in fmt.format_ticks(ticks)])
    gaps = np.diff(ticks) / (hi - lo) * room_pt
    return bool(np.all(gaps >= half[:-1] + half[1:]))


def fit_suptitle(fig, room: float = 0.98) -> None:
    """Wrap the lines of a suptitle wider than ``room`` of its figure at word breaks
    (long titles, with ``[--quick]`` appended, were cut at both edges of the figure):
    each line is refilled to a character count scaled by how much too wide it is, and
    measured again."""
    import textwrap

    title = getattr(fig, "_suptitle", None)  # (Figure.get_suptitle returns the text only)
    if title is None or not title.get_text():
        return
    renderer = fig.canvas.get_renderer()
    width = room * fig.bbox.width
    for _ in range(6):  # proportional estimates converge in a step or two
        extent = title.get_window_extent(renderer).width
        if extent <= width:
            return
        lines = title.get_text().split("\n")
        longest = max(len(line) for line in lines)
        chars = max(20, int(longest * width / extent) - 1)
        wrapped = [textwrap.fill(line, chars) if len(line) > chars else line for line in lines]
        title.set_text("\n".join(wrapped))


def _lay_out_once(fig, dpi: float) -> None:
    """Run the figure's layout engine once, at the saving resolution, and remove it.

    ``savefig`` draws a figure twice while it has any layout engine (a draw whose only
    use is the layout it starts, then the drawing itself), even the placeholder
    ``"none"`` leaves: here the engine runs as that first draw runs it (at the saving
    resolution, before anything is drawn) and then leaves, so each format is drawn once,
    every file byte for byte as before, for about a quarter less CPU time (a figure of
    fifteen panels: 1.2 to 0.9 CPU-s)."""
    engine = fig.get_layout_engine()
    if engine is None:
        return
    fig.set_dpi(dpi)
    if fig.axes:  # as Figure.draw runs it
        try:
            engine.execute(fig)
        except ValueError:  # Figure.draw draws such a figure without its layout
            pass
    fig.set_layout_engine(None)  # None: no engine (where rcParams ask for none)
    if fig.get_layout_engine() is not None:  # rcParams asked for one: keep its positions
        fig.set_layout_engine("none")


def save(
    fig, stem: Path, formats: tuple[str, ...] = ("png", "svg"), dpi: float = DPI
) -> list[Path]:
    """Write ``<stem>.png`` and ``<stem>.svg`` (names may hold dots), each atomically (a
    figure stopped mid-write leaves the one before it, never half a file); close the
    figure. Returns the files there: those written, and in a folder the system refuses to
    write (:func:`~kalman_vs_infoset.experiments.files.derived_write` warns) those an
    earlier command wrote; never a file that does not exist."""
    plain_log_labels(fig)
    stem = Path(stem)
    out = []
    try:
        fig.set_dpi(dpi)  # (measured at the saving resolution, as the layout below)
        fit_suptitle(fig)
        _lay_out_once(fig, dpi)
        thin_crowded_ticks(fig)
        for ext in formats:
            p = stem.parent / f"{stem.name}.{ext}"
            # the temporary file's name ends in .tmp: the format is given, not guessed
            if derived_write(p, partial(fig.savefig, format=ext, dpi=dpi)) or p.is_file():
                out.append(p)
    finally:
        plt.close(fig)
    return out
