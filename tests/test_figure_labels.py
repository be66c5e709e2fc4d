"""What the figures say, read from the matplotlib objects: a review of every figure the
commands draw found runs that diverged drawn as ordinary results, a reference line
called a floor that runs fall below, the paper's marks called "seed", suptitles cut at
both edges, an axis label running into the panel above and a log axis whose zeros
vanish without a word. Each test fails without its fix."""

import numpy as np
import pandas as pd
from harness_texts import small_attitude_trace
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments import plots, plots_attitude
from kalman_vs_infoset.experiments.cli import main


def _legend_texts(fig) -> list[str]:
    texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    for ax in fig.axes:
        if ax.get_legend():
            texts += [t.get_text() for t in ax.get_legend().get_texts()]
    return texts


def test_a_cdf_says_how_many_drawn_runs_diverged():
    """An intercept run that diverged has a miss (kilometres) and a fuel (0): its curve
    was labelled "(n=3)" like any other; the label now says how many of them diverged."""
    rows = [{"estimator": "box", "noise": "random", "miss_m": 7000.0 + j, "fuel_mps": 0.0,
             "status": "ok", "diverged": j < 2} for j in range(3)]  # fmt: skip
    rows += [{"estimator": "infoset", "noise": "random", "miss_m": 1.0 + j, "fuel_mps": 100.0,
              "status": "ok", "diverged": False} for j in range(3)]  # fmt: skip
    fig = plots.cdf_figure(pd.DataFrame(rows), ["estimator", "noise"], "t")
    texts = _legend_texts(fig)
    box = [t for t in texts if t.startswith(fs.words("box"))]
    info = [t for t in texts if t.startswith(fs.words("infoset"))]
    assert box and all("n=3 of which 2 diverged" in t for t in box), texts
    assert info and not any("diverged" in t for t in info)
    fs.plt.close(fig)


def test_fig5_marks_the_paper_and_the_miss_scale_in_words(tmp_path):
    """The marks read "seed Fig. 3 random" (taken for a random seed) and "bearing floor"
    (runs end below it: it is a scale); the title named the estimator by its registry
    name. They read as paper-figures writes them."""
    captured = {}
    real = plots.cdf_figure

    def spy(table, by, title, marks, *a, **k):
        captured.update(title=title, marks=marks)
        return real(table, by, title, marks, *a, **k)

    plots.cdf_figure = spy
    try:
        assert main(["fig5", "--runs", "1", "--out", str(tmp_path), "--workers", "1",
                     "--no-progress"]) == 0  # fmt: skip
    finally:
        plots.cdf_figure = real
    labels = [lab for marks in captured["marks"].values() for _, lab in marks]
    assert "paper Fig. 3 (one engagement), random errors" in labels
    assert "bearing-limited miss scale" in labels
    assert not any(lab.startswith("seed") or "floor" in lab for lab in labels)
    assert fs.words("infoset") in captured["title"] and "Seed 003" not in captured["title"]


def test_a_suptitle_wider_than_its_figure_is_wrapped_at_word_breaks(tmp_path):
    """A suptitle of 120 characters on a figure 6 inches wide was cut at both edges;
    saved, every line of it lies within the figure, and its words are all there."""
    fig, axes = fs.figure(1, 1, size=(6.0, 3.0))
    axes[0, 0].plot([0, 1], [0, 1])
    words = " ".join(f"word{i}" for i in range(20))
    fig.suptitle(words)
    fs.fit_suptitle(fig)
    renderer = fig.canvas.get_renderer()
    box = fig._suptitle.get_window_extent(renderer)
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width
    assert fig._suptitle.get_text().split() == words.split()
    assert "\n" in fig._suptitle.get_text()
    short = fs.figure(1, 1, size=(6.0, 3.0))[0]
    short.suptitle("a short title")
    fs.fit_suptitle(short)
    assert short._suptitle.get_text() == "a short title"  # left as it is
    fs.save(fig, tmp_path / "wide")
    fs.plt.close(short)


def test_attitude_histories_label_the_energy_in_two_lines_and_say_log_zeros():
    """The energy panel's label ("energy index sum M^2 dt, ...", longer than the panel)
    ran into the label above it and wrote M^2 where the CDFs write M^T M; a rate norm of
    0 at the start vanished off the log axis without a word; and each run was in the
    legend three times ("...: error angle", "...: energy so far", "...: rate norm")."""
    trace = small_attitude_trace(4)
    trace.loc[(trace["axis"] == 1) & (trace["t_s"] == 0.0), "rate_norm_degps"] = 0.0
    fig = plots_attitude.time_histories([trace], "t")
    bottom = fig.axes[-3:]
    energy = bottom[1].get_ylabel()
    assert "M^T M" in energy and "\n" in energy and "N^2 m^2 s" in energy
    assert "zeros not drawn" in bottom[2].get_ylabel() and bottom[2].get_yscale() == "log"
    assert "zeros not drawn" not in bottom[0].get_ylabel()  # no zero angle there
    texts = _legend_texts(fig)
    run = fs.words("box", "random")
    assert texts.count(run) == 1 and not any(t.startswith(run + ":") and "bound" not in t
                                             for t in texts)  # fmt: skip
    fs.plt.close(fig)
    assert np.isfinite(trace["t_s"]).all()


def test_tightness_sweep_and_compare_labels_carry_units_and_words(tmp_path, monkeypatch):
    """The tightness figure's ratio axis had no unit and its title the registry name
    ("infoset vs exact set, game noise"); the sweep's fuel axis read "fuel (sum of
    |impulses|) (mean over runs), m/s"; compare's miss mark was "bearing floor"."""
    from kalman_vs_infoset.experiments import cmd_tightness

    saved = []
    monkeypatch.setattr(fs, "save", lambda fig, stem, **k: saved.append(fig) or [])
    result = {"scenario": "kp_fig3", "estimator": "infoset", "noise": "game", "seed": 3,
              "guided": True, "times_s": [10.0], "set_lo_m": [-2.0], "set_hi_m": [2.0],
              "exact_lo_m": [-1.0], "exact_hi_m": [1.0], "truth_w_m": [0.0],
              "ratio": [2.0]}  # fmt: skip
    monkeypatch.setattr(cmd_tightness, "atomic_write", lambda *a, **k: None, raising=False)
    try:
        cmd_tightness._write(result, tmp_path / "t")
    except (IndexError, TypeError):  # (its JSON path list: not what is checked here)
        pass
    (fig,) = saved
    assert fig.axes[1].get_ylabel().endswith(", -")
    title = fig._suptitle.get_text()
    assert fs.words("infoset") in title and "game errors" in title and "vs exact" not in title
    table = pd.DataFrame({"value": ["1", "10"], "estimator": ["ekf", "ekf"],
                          "noise": ["random", "random"], "miss_m_mean": [1.0, 2.0],
                          "fuel_mps_mean": [3.0, 4.0]})  # fmt: skip
    sweep = plots.sweep_figure(table, "k", "t")
    assert [ax.get_ylabel() for ax in sweep.axes[:2]] == [
        "mean miss distance, m", "mean fuel (sum of |impulses|), m/s"]  # fmt: skip
    fs.plt.close("all")
    marks = {}
    real = plots.cdf_figure

    def spy(table, by, title, given, *a, **k):
        marks.update(given)
        return real(table, by, title, given, *a, **k)

    monkeypatch.setattr(plots, "cdf_figure", spy)
    argv = ["compare", "kp_fig3", "--estimators", "ekf,ukf", "--noise", "random", "--runs",
            "1", "--workers", "1", "--no-progress", "--out", str(tmp_path / "c")]  # fmt: skip
    assert main(argv) == 0
    assert [label for _, label in marks["miss_m"]] == ["bearing-limited miss scale"]
    # "perfect info", where fig5 says it in words
    assert [label for _, label in marks["fuel_mps"]] == ["perfect information (mean)"]


def test_the_gain_study_figures_have_titles_and_say_paper_not_seed(tmp_path, monkeypatch):
    """Fig. 14's redrawing had no title, and its labels read "seed table", "seed eq.
    (28), rad, / 2" (a seed is a random seed to most readers)."""
    from kalman_vs_infoset.experiments import cmd_pd_gains

    drawn = {}
    monkeypatch.setattr(
        cmd_pd_gains, "_save", lambda fig, out, name: drawn.update({name: fig}) or []
    )
    argv = ["pd-gains", "--angles-deg", "1,5", "--grid-step", "0.2", "--out", str(tmp_path)]
    assert main(argv) == 0
    assert set(drawn) == {"fig10_settle_map", "fig14_f0", "fig15_settle_vs_angle"}
    for name, fig in drawn.items():
        (ax,) = [a for a in fig.axes if a.get_legend()]
        assert ax.get_title(), name
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert not any(lab.lower().startswith("seed") or "seed " in lab for lab in labels), labels
    fs.plt.close("all")


def test_curves_and_marks_together_put_the_legend_below_the_panels():
    """Fig. 5's four curves and three reference marks a panel made a legend of seven
    entries inside the fuel panel, over the game runs' curves: a panel's curves and
    marks together decide, and the legend goes below both panels."""
    rows = [{"variant": v, "noise": n, "miss_m": 1.0 + j, "fuel_mps": 100.0 + j,
             "status": "ok"} for v in ("a", "b") for n in ("random", "game")
            for j in range(3)]  # fmt: skip
    marks = {"miss_m": [(4.3, "paper r"), (9.5, "paper g"), (1.15, "scale")],
             "fuel_mps": [(244.7, "paper r"), (521.7, "paper g"), (44.8, "perfect")]}  # fmt: skip
    fig = plots.cdf_figure(pd.DataFrame(rows), ["variant", "noise"], "t", marks)
    assert fig.legends and not any(ax.get_legend() for ax in fig.axes)
    fs.plt.close(fig)
    few = plots.cdf_figure(
        pd.DataFrame(rows), ["variant", "noise"], "t", {"miss_m": marks["miss_m"][:1]}
    )
    assert not few.legends and all(ax.get_legend() for ax in few.axes)  # 5 entries: inside
    fs.plt.close(few)


def test_a_figure_legend_wider_than_its_figure_takes_fewer_columns():
    """Four columns of long labels (fig5's reference marks) made a legend wider than the
    figure, cut at both edges; it takes fewer columns until it fits."""
    fig, axes = fs.figure(1, 2, size=(11.0, 4.4))
    for i in range(11):
        axes[0, i % 2].plot(
            [0, 1], [i, i], label=f"paper Fig. 3 (one engagement), mark {i}: 24{i}.7"
        )
    fs.figure_legend(fig, axes[0], fontsize=7, ncol=4)
    (leg,) = fig.legends
    box = leg.get_window_extent(fig.canvas.get_renderer())
    assert box.width <= fig.bbox.width and leg._ncols < 4
    fs.plt.close(fig)


def test_a_cdf_mark_says_its_unit():
    """A CDF's reference marks read "bearing-limited miss scale: 1.15" and "perfect
    information (mean): 79.98": below the panels, one legend holds the miss panel's and
    the fuel panel's marks, and the numbers had no unit. Each now says its axis's."""
    rows = [{"estimator": "infoset", "noise": n, "miss_m": 1.0 + j, "fuel_mps": 100.0 + j,
             "status": "ok"} for j in range(3) for n in ("random", "game", "bias")]  # fmt: skip
    marks = {"miss_m": [(1.15, fs.MISS_SCALE_MARK), (9.5, "paper Fig. 3, game errors")],
             "fuel_mps": [(79.98, fs.PERFECT_INFO_MARK)]}  # fmt: skip
    fig = plots.cdf_figure(pd.DataFrame(rows), ["estimator", "noise"], "t", marks)
    texts = _legend_texts(fig)
    assert f"{fs.MISS_SCALE_MARK}: 1.15 m" in texts, texts
    assert "paper Fig. 3, game errors: 9.5 m" in texts
    assert f"{fs.PERFECT_INFO_MARK}: 79.98 m/s" in texts
    fs.plt.close(fig)
