"""The trace figures as a reader sees them (checked through matplotlib's objects, on
small synthetic traces, no engagement run):

* the control processes' "ours: miss" ring sits where the truth's own signed forecast
  ends (a box run whose truth ends at -7002 m had its ring at +6991 m, across zero),
  and the paper's unsigned miss is a pair of stars, one each side of zero;
* the forecast-miss panels' legends lie inside the figure, within their panel's width
  and over no axes (in the two-column layout the legend spilled over the y label; in
  the overlay it covered the intervals);
* the symmetric-log axes say so in their labels, and the overlay's "truth outside its
  belief" ticks are in a strip of their own, not on the data axis about 0;
* the set figures' titles and legends and the attitude traces' titles are in words:
  scenario, estimator, noise, seed and run.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments import plots_attitude, plots_intercept, plots_sets, plots_traces
from matplotlib.transforms import Bbox

N = 40


def _steps(estimator: str, noise: str, truth_end: float, miss: float, outside=()) -> pd.DataFrame:
    """One run of one channel: the truth's forecast goes from 5 km to ``truth_end``
    inside an interval of +-20 km about it (wider than any data: fills its panel)."""
    t = np.arange(N) * 0.5
    truth = np.linspace(5000.0, truth_end, N)
    inside = np.ones(N, dtype=bool)
    inside[list(outside)] = False
    return pd.DataFrame(
        {
            "scenario": "kp_fig5", "estimator": estimator, "noise": noise, "seed": 5,
            "run": 0, "step": np.arange(N), "t_s": t, "channel": "lateral",
            "alpha_true_rad": -1e-3 * t, "alpha_meas_rad": -1e-3 * t + 1e-4,
            "alpha_err_rad": 1e-4, "alpha_bound_rad": 2e-4,
            "forecast_lo_m": truth - 2e4, "forecast_hi_m": truth + 2e4,
            "forecast_true_m": truth, "truth_inside": inside,
            "impulse_mps": 0.0, "fuel_mps": np.linspace(0.0, 10.0, N), "miss_m": miss,
            "x_true_m": 5.8e6, "zem_true_m": 0.0,
        }
    )  # fmt: skip


def _box_run() -> pd.DataFrame:
    return pd.concat(
        [_steps("box", n, -7001.6, 6991.2) for n in ("random", "game")], ignore_index=True
    )


def _drawn(fig):
    fig.canvas.draw()  # runs the constrained layout: the final positions
    return fig.canvas.get_renderer()


def _inside(inner: Bbox, outer: Bbox, tol: float = 1.0) -> bool:
    return (
        inner.x0 >= outer.x0 - tol
        and inner.x1 <= outer.x1 + tol
        and inner.y0 >= outer.y0 - tol
        and inner.y1 <= outer.y1 + tol
    )


# -- control processes -------------------------------------------------------------------
def test_the_ring_sits_where_the_truth_s_signed_forecast_ends():
    paper = {"random": (4.3, 244.7, "paper"), "game": (9.5, 521.7, "paper")}
    fig = plots_intercept.control_processes(_box_run(), 0, "box", ["random", "game"], paper=paper)
    panels = [a for a in fig.axes if a.get_ylabel().startswith("forecast miss Pi, m")]
    assert len(panels) == 2
    for ax, p_miss in zip(panels, (4.3, 9.5), strict=True):
        (ring,) = [ln for ln in ax.get_lines() if ln.get_label().startswith("ours: miss")]
        assert "6991.2 m" in ring.get_label()
        assert list(ring.get_ydata()) == pytest.approx([-7001.6])  # not +6991.2
        (stars,) = [ln for ln in ax.get_lines() if ln.get_label().startswith("paper: miss")]
        assert sorted(stars.get_ydata()) == pytest.approx([-p_miss, p_miss])
    fs.plt.close(fig)


def test_the_forecast_panel_s_legend_fits_its_panel_below_it_in_two_columns():
    """Two columns (compare, ``kvi plot``): the legend was wider than its panel and
    spilled past the left edge over the y label, and covered the interval."""
    fig = plots_intercept.control_processes(_box_run(), 0, "box", ["random", "game"])
    renderer = _drawn(fig)
    figure_box = fig.bbox
    panels = [a for a in fig.axes if a.get_ylabel().startswith("forecast miss Pi, m")]
    for ax in panels:
        leg = ax.get_legend()
        box = leg.get_window_extent(renderer)
        panel = ax.get_window_extent(renderer)
        assert _inside(box, figure_box)
        assert box.x0 >= panel.x0 - 1 and box.x1 <= panel.x1 + 1  # within its panel's width
        for other in fig.axes:  # over no axes: no data covered
            assert not box.overlaps(other.get_window_extent(renderer)), other.get_ylabel()
        assert box.y1 <= panel.y0  # below its panel
    fs.plt.close(fig)


def test_the_symmetric_log_axes_say_their_scale():
    fig = plots_intercept.control_processes(_box_run(), 0, "box", ["random"])
    (ax,) = [a for a in fig.axes if a.get_yscale() == "symlog"]
    label = ax.get_ylabel()
    assert "symmetric log" in label and "linear within ±10 m" in label
    fs.plt.close(fig)


# -- overlay -----------------------------------------------------------------------------
def _overlay_steps() -> pd.DataFrame:
    return pd.concat(
        [
            _steps("box", "random", -20.0, 20.0),
            _steps("ekf", "random", -5.0, 5.0, outside=range(20, 30)),
            _steps("ukf", "random", 3.0, 3.0, outside=range(5, 12)),
            _steps("infoset", "random", 2.0, 2.0),
        ],
        ignore_index=True,
    )


def test_the_overlay_s_legend_covers_no_interval_and_stays_in_the_figure():
    fig = plots_intercept.estimator_overlay(_overlay_steps(), 0, "random")
    renderer = _drawn(fig)
    top = fig.axes[0]
    leg = top.get_legend()
    box = leg.get_window_extent(renderer)
    assert len(leg.get_texts()) >= 5
    assert _inside(box, fig.bbox)
    for ax in [*fig.axes, *top.child_axes]:  # the panels and the strip of outside ticks
        assert not box.overlaps(ax.get_window_extent(renderer))
    fs.plt.close(fig)


def test_the_overlay_s_outside_ticks_are_in_a_strip_not_on_the_data_axis():
    fig = plots_intercept.estimator_overlay(_overlay_steps(), 0, "random")
    renderer = _drawn(fig)
    top = fig.axes[0]
    label = top.get_ylabel()
    assert "symmetric log" in label and "linear within ±10 m" in label
    # on the data axis: no tick of the outside marks (only their empty legend handles)
    marks = [ln for ln in top.get_lines() if ln.get_marker() == "|"]
    assert marks and all(len(ln.get_xdata()) == 0 for ln in marks)
    (strip,) = top.child_axes
    rows = {ln.get_label(): ln for ln in strip.get_lines()}
    assert set(rows) == {f"{fs.words(e)}: truth's state outside its belief (strip)"
                         for e in ("ekf", "ukf")}  # fmt: skip
    assert (
        len(rows[f"{fs.words('ekf')}: truth's state outside its belief (strip)"].get_xdata()) == 10
    )
    names = [t.get_text() for t in strip.get_yticklabels()]
    assert names == [fs.words("ekf"), fs.words("ukf")]
    # the strip lies below the panel, apart from it
    assert strip.get_window_extent(renderer).y1 <= top.get_window_extent(renderer).y0
    legend_texts = {t.get_text() for t in top.get_legend().get_texts()}
    assert set(rows) <= legend_texts
    fs.plt.close(fig)


# -- sets --------------------------------------------------------------------------------
def _sets(noise: str) -> pd.DataFrame:
    """One square section per snapshot: prior and posterior at t = 1 s, posterior at 2 s."""
    rows = []
    for step, t, phase, half in ((2, 1.0, "prior", 2e-4), (2, 1.0, "posterior", 1e-4),
                                 (4, 2.0, "posterior", 5e-5)):  # fmt: skip
        for v, (a, w) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
            rows.append({"run": 0, "step": step, "t_s": t, "phase": phase,
                         "channel": "lateral", "estimator": "infoset", "section": 0,
                         "vertex": v, "x_m": 5.8e6, "alpha_rad": a * half,
                         "zem_m": w * 1e3 * half / 1e-4, "scenario": "kp_fig5",
                         "noise": noise, "seed": 5})  # fmt: skip
    return pd.DataFrame(rows)


@pytest.mark.parametrize("noise", ["random", "game"])
def test_the_slices_say_the_noise_and_the_estimator_in_words(noise):
    fig = plots_sets.slices(_sets(noise), 0)
    title = fig.get_suptitle()
    assert fs.NOISE_WORDS[noise] in title and fs.words("infoset") in title
    assert "seed 5" in title and "run 0" in title
    texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert "information set: sections at their ranges" in texts
    assert not any(t.startswith("infoset:") for t in texts)
    fs.plt.close(fig)


def test_the_set3d_title_is_in_words(tmp_path, monkeypatch):
    titles: dict[str, str] = {}

    def save(fig, stem, *args, **kw):
        titles[stem.name] = fig.get_suptitle()
        fs.plt.close(fig)
        return []

    monkeypatch.setattr(fs, "save", save)
    sets = _sets("random")
    steps = _steps("infoset", "random", 1.0, 1.0)
    path = tmp_path / "kp_fig5-infoset-random-s5-trace.parquet"
    plots_traces._set_figures(path, steps, sets, tmp_path, animation=False)
    title = titles["kp_fig5-infoset-random-s5-run0-set3d"]
    assert "kp_fig5-infoset" not in title  # not the file stem
    for part in ("kp_fig5", "information set", "random errors", "seed 5", "run 0"):
        assert part in title, title


# -- attitude ----------------------------------------------------------------------------
def test_each_attitude_trace_s_time_histories_name_estimator_noise_and_run(tmp_path, monkeypatch):
    """``kvi plot`` on an attitude folder: one figure per trace, each titled with its
    own estimator, noise and runs (all were "smallsat_rw: time histories")."""
    for est in ("ukf", "box"):
        n = 3
        pd.DataFrame(
            {"step": np.repeat(np.arange(n), 3), "t_s": np.repeat(np.arange(n) * 0.1, 3),
             "axis": np.tile([1, 2, 3], n), "run": 0, "scenario": "smallsat_rw",
             "controller": "pd", "estimator": est, "noise": "random", "seed": 0}
        ).to_parquet(tmp_path / f"smallsat_rw-pd-{est}-random-s0-trace.parquet")  # fmt: skip
    titles = []

    def time_histories(traces, title=""):
        titles.append(title)
        return None

    monkeypatch.setattr(plots_attitude, "time_histories", time_histories)
    monkeypatch.setattr(fs, "save", lambda fig, stem, *a, **kw: [])
    plots_traces.plot_files(sorted(tmp_path.glob("*-trace.parquet")), out=tmp_path)
    assert set(titles) == {
        f"smallsat_rw, pd controller: time histories, {fs.words(e)}, random errors, run 0 (seed 0)"
        for e in ("box", "ukf")
    }
