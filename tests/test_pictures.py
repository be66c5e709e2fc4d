"""Traces and figures: what a trace holds, that recording only observes, and
that every figure is fit for print (checked through matplotlib's objects, not pixels).

Every figure the package saves goes through :func:`kalman_vs_infoset.experiments.figstyle.save`; the
``checked`` fixture wraps it so that each figure is inspected before it is written:
every visible axis has x and y (and z) labels naming a unit after a comma, and every
line and labelled patch collection has an entry in a legend of its figure.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest
from docs_numbers import ROOT
from harness_texts import TINY_RW
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.base import PointBelief
from kalman_vs_infoset.estim.intercept.describe import describe_channel, fields
from kalman_vs_infoset.estim.intercept.model import ChannelModel
from kalman_vs_infoset.experiments import figstyle
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.intercept import run_engagement
from kalman_vs_infoset.experiments.sim.trace import Recorder
from kalman_vs_infoset.experiments.traces import intercept_trace
from matplotlib.collections import QuadMesh
from matplotlib.lines import Line2D

UNIT = re.compile(r", \S")
STEP_FIELDS = {
    "alpha_true_rad", "alpha_meas_rad", "alpha_err_rad", "alpha_bound_rad", "range_meas_m",
    "forecast_true_m", "zem_true_m", "truth_inside", "impulse_mps", "fuel_mps", "step", "t_s",
    "channel", "run", "estimator", "noise", "miss_m", *fields(),
}  # fmt: skip


def figure_problems(fig) -> list[str]:
    """What keeps a figure from being fit for print (labels, units, legend entries)."""
    legends = [ax.get_legend() for ax in fig.axes] + list(fig.legends)
    entries = {t.get_text() for leg in legends if leg is not None for t in leg.get_texts()}
    bad = []
    for ax in fig.axes:
        if not ax.get_visible() or hasattr(ax, "_colorbar"):
            continue
        names = ["x", "y"] + (["z"] if hasattr(ax, "get_zlabel") else [])
        for name in names:
            label = getattr(ax, f"get_{name}label")()
            if name == "x" and not label:  # a shared x axis is labelled once, below
                label = " ".join(a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax))
            if not UNIT.search(label):
                bad.append(f"{ax.get_title()!r}: {name} label {label!r} names no unit")
        artists = list(ax.get_lines()) + [c for c in ax.collections if not isinstance(c, QuadMesh)]
        for art in artists:
            label = art.get_label()
            if isinstance(art, Line2D) and len(art.get_xdata()) == 0 and label in entries:
                continue  # a legend handle
            if label.startswith("_") or label not in entries:
                bad.append(f"{ax.get_title()!r}: {type(art).__name__} {label!r} not in a legend")
    return bad


@pytest.fixture
def checked(monkeypatch):
    """Every figure saved while the test runs is checked; their names are collected."""
    saved: list[str] = []
    original = figstyle.save

    def save(fig, stem, *args, **kw):
        problems = figure_problems(fig)
        assert not problems, f"{stem}:\n" + "\n".join(problems)
        saved.append(str(stem))
        return original(fig, stem, *args, **kw)

    monkeypatch.setattr(figstyle, "save", save)
    return saved


SHORT = [  # the Fig. 3 engagement started 290 km out: 10 s, 20 steps
    "truth.x_km=[290.0, 290.0]",
    "estimator.x_km=[250.0, 330.0]",
]


@pytest.fixture(scope="module")
def short():
    return load_scenario(str(ROOT / "data/scenarios/kp_fig3.toml"), SHORT)


# -- traces ------------------------------------------------------------------------------
def _short_kp_fig3(tmp_path) -> Path:
    """kp_fig3 (same name, so the same file names) started 290 km out (``SHORT``): the
    trace commands draw and check every step of a 20-step approach instead of ~200."""
    p = tmp_path / "short.toml"
    text = open(ROOT / "data/scenarios/kp_fig3.toml").read()
    text = text.replace("x_km = [5801.3, 5801.3]", "x_km = [290.0, 290.0]")
    p.write_text(text.replace("x_km = [5301.3, 6301.3]", "x_km = [250.0, 330.0]"))
    return p


def test_intercept_trace_command(tmp_path, capsys, checked):
    """The judged command: one row per step with the fields; the set's traced forecast-miss
    interval holds the truth's forecast on every row; the trace is the table's run."""
    out = tmp_path / "out"
    args = ["intercept", str(_short_kp_fig3(tmp_path)), "--noise", "game", "--trace", "0"]
    assert main([*args, "--json", "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    table = pd.read_parquet(out / "kp_fig3-infoset-game-s3.parquet")
    trace = pd.read_parquet(out / "_traces" / "kp_fig3-infoset-game-s3-trace.parquet")
    assert STEP_FIELDS <= set(trace.columns)
    assert len(trace) == int(table["steps"].iloc[0]) and trace["step"].is_unique
    assert (trace["forecast_lo_m"] <= trace["forecast_true_m"]).all()
    assert (trace["forecast_true_m"] <= trace["forecast_hi_m"]).all()
    assert trace["truth_inside"].all() and (trace["status"] == "ok").all()
    assert trace["fuel_mps"].iloc[-1] == pytest.approx(table["fuel_mps"].iloc[0], rel=1e-12)
    assert trace["miss_m"].iloc[0] == pytest.approx(result["miss_m"]["mean"], rel=1e-12)
    assert (trace["n_sections"] > 0).all() and (trace["area_max_radm"] > 0).all()
    assert any(f.endswith("-trace-sets.parquet") for f in result["files"])
    assert any(f.endswith(".gif") for f in result["files"])
    assert {"kp_fig3-infoset-game-s3-run0-processes", "kp_fig3-infoset-game-s3-run0-set3d"} <= {
        s.rsplit("/", 1)[-1] for s in checked
    }


@pytest.mark.parametrize("estimator", registry.names("intercept"))
def test_every_registered_estimator_traces(short, estimator):
    steps, sets, results = intercept_trace(short, estimator, "random", 2, [0], sets_every=5)
    plain = run_engagement(short, estimator, "random", np.random.default_rng(
        np.random.SeedSequence(2, spawn_key=(0,))))  # fmt: skip
    assert results[0] == plain  # recording only observes
    assert len(steps) == plain.steps and STEP_FIELDS <= set(steps.columns)
    live = steps[~steps["empty"]]
    for col in ("forecast_lo_m", "forecast_hi_m", "zem_lo_m", "alpha_lo_rad", "x_hi_m"):
        assert np.isfinite(live[col]).all(), col
    assert (live["forecast_lo_m"] <= live["forecast_hi_m"]).all()
    if estimator == "infoset":
        assert len(sets) and {"alpha_rad", "zem_m", "x_m", "phase"} <= set(sets.columns)


def test_describe_takes_the_generic_route_for_any_belief():
    """A belief with nothing but the interface (a point) still gives every field."""
    model = ChannelModel()
    d = describe_channel(PointBelief(np.array([1e-3, 2e-6, 5e6])), model)
    assert set(d) == set(fields())
    assert (
        d["forecast_lo_m"]
        == d["forecast_hi_m"]
        == pytest.approx(float(model.miss_forecast_m(np.array([1e-3, 2e-6, 5e6]))))
    )
    assert d["alpha_lo_rad"] == d["alpha_hi_rad"] == 1e-3 and np.isnan(d["n_sections"])


def test_recorder_keeps_sets_when_asked():
    rec = Recorder(sets_every=0)
    assert not rec.wants_sets(0) and not rec.wants_prior(0)
    rec = Recorder(sets_every=10, sets_first=3)
    assert [s for s in range(25) if rec.wants_sets(s)] == [0, 1, 2, 10, 20]


def test_compare_trace_overlays_estimators(tmp_path, capsys, checked, monkeypatch):
    p = _short_kp_fig3(tmp_path)
    args = ["compare", str(p), "--estimators", "infoset,ukf", "--noise", "game"]
    assert main([*args, "--trace", "0", "--out", str(tmp_path / "o"), "--workers", "1",
                 "--no-progress", "--json"]) == 0  # fmt: skip
    files = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["files"]
    names = {f.rsplit("/", 1)[-1] for f in files}
    assert {"kp_fig3-game-s3-run0-overlay.png", "kp_fig3-game-s3-run0-overlay.svg"} <= names
    assert "kp_fig3-infoset-game-s3-run0-processes.png" in names
    traces = sorted(f for f in files if f.endswith("-trace.parquet"))
    assert len(traces) == 2
    # the plot command redraws a trace (the UKF's: no sets), marking the paper's numbers
    assert main(["plot", traces[1], "--out", str(tmp_path / "p")]) == 0
    assert (tmp_path / "p" / "kp_fig3-ukf-game-s3-run0-processes.svg").exists()
    capsys.readouterr()
    # the results folder stands for its traces: both, as when named (handed to the
    # drawing drawn above, not drawn again)
    from kalman_vs_infoset.experiments import cmd_plot

    handed: list = []
    monkeypatch.setattr(cmd_plot, "plot_files", lambda paths, **kw: handed.extend(paths) or [])
    assert main(["plot", str(tmp_path / "o"), "--no-animation", "--json"]) == 0
    drawn = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert sorted(drawn["traces"]) == traces == sorted(map(str, handed))


def test_trace_arguments_are_checked(tmp_path, capsys):
    args = ["intercept", str(ROOT / "data/scenarios/kp_fig3.toml"), "--out", str(tmp_path)]
    for bad in ("x", "0,0", "-1", ""):
        with pytest.raises(SystemExit) as exc:
            main([*args, "--trace", bad])
        assert exc.value.code == 2
    assert main([*args, "--trace", "1"]) == 2  # only run 0 exists
    assert "--trace 1" in capsys.readouterr().err
    assert main(["plot", str(tmp_path / "none.parquet")]) == 2
    (tmp_path / "empty").mkdir()
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "empty")]) == 2  # a folder without traces
    assert "no trace files in this folder" in capsys.readouterr().err


def test_default_attitude_run_draws_time_histories(tmp_path, capsys, checked):
    p = tmp_path / "tiny_rw.toml"
    p.write_text(TINY_RW)
    out = tmp_path / "out"
    args = ["attitude", str(p), "--noise", "random", "--estimators", "box,perfect"]
    assert main([*args, "--out", str(out), "--json", "--no-progress"]) == 0
    files = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["files"]
    assert any(f.endswith("-history.png") for f in files)
    assert not any(f.endswith("-cdf.png") for f in files)  # one run: no CDF
    table = pd.read_parquet(out / "tiny_rw-pd-box-random-s0.parquet")
    trace = pd.read_parquet(out / "_traces" / "tiny_rw-pd-box-random-s0-trace.parquet")
    assert set(trace["axis"]) == {1, 2, 3} and len(trace) == 3 * 101
    last = trace[trace["step"] == trace["step"].max()]
    assert last["energy_N2m2s"].iloc[0] == pytest.approx(table["energy_N2m2s"].iloc[0])
    assert trace["truth_inside"].all()
    # more runs: the CDF, and histories only of the traced runs
    assert main([*args, "--out", str(out / "b"), "--runs", "2", "--json", "--no-progress"]) == 0
    files = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["files"]
    assert any(f.endswith("-cdf.png") for f in files)
    assert not any(f.endswith("-history.png") for f in files)


# -- figures --------------------------------------------------------------------------------
def test_style_is_colour_blind_safe_and_consistent():
    palette = set(figstyle.OKABE_ITO.values())
    for name in ("infoset", "ekf", "ukf", "box", "perfect"):
        assert figstyle.estimator_colour(name) in palette
    assert figstyle.estimator_colour("zonotope") == figstyle.estimator_colour("zonotope")
    # every registered estimator of a domain has a colour of its own (one figure each)
    for domain in ("intercept", "attitude"):
        colours = [figstyle.estimator_colour(n) for n in registry.names(domain)]
        assert len(set(colours)) == len(colours), domain
    kinds = ("random", "game", "bias", "none", "targeted", "lookahead", "switch")
    assert len({str(figstyle.noise_style(n)) for n in kinds}) == len(kinds)
    assert matplotlib.get_backend().lower() == "agg"


def _read_plain_label(text: str) -> float:
    """The number of a plain log label: "0", "10⁴", "−10⁻³", "2×10⁻³"."""
    sign = -1.0 if text.startswith("−") else 1.0
    text = text.removeprefix("−")
    if text == "0":
        return 0.0
    coeff, _, power = text.rpartition("10")
    exponent = int(power.translate(str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")))
    return sign * float(coeff.removesuffix("×") or 1.0) * 10.0**exponent


def test_log_axes_are_labelled_in_plain_text_at_their_ticks(tmp_path):
    """Log and symlog tick labels are written without mathtext ("10⁻³", "−10⁴",
    "2×10⁻³"): every label, read back as a number, is the value of its tick."""
    import matplotlib.pyplot as plt

    fig, (ax_log, ax_sym, ax_minor) = plt.subplots(1, 3)
    ax_log.plot([1e-3, 1e4], [1, 2], label="a")
    ax_log.set(xscale="log", xlabel="x, m", ylabel="y, -")
    ax_sym.plot([0, 1], [-1e4, 1e4], label="b")
    ax_sym.set(yscale="symlog", xlabel="x, m", ylabel="y, m")
    ax_minor.plot([1, 2], [2e-3, 9e-3], label="c")  # within a decade: minor ticks labelled
    ax_minor.set(yscale="log", xlabel="x, m", ylabel="y, m")
    figstyle.save(fig, tmp_path / "logs")
    axes = [(ax_log.xaxis, False), (ax_sym.yaxis, False), (ax_minor.yaxis, True)]
    labelled = {}
    for axis, minor in axes:
        ticks = axis.get_minor_ticks() if minor else axis.get_major_ticks()
        for tick in ticks:
            text = tick.label1.get_text()
            assert "$" not in text
            if text:
                labelled[text] = tick.get_loc()
    assert {"10⁻³", "10⁰", "10⁴", "−10⁴", "0"} <= set(labelled)
    assert any("×10⁻³" in text for text in labelled)
    for text, loc in labelled.items():
        assert _read_plain_label(text) == pytest.approx(loc, rel=1e-12), text


def test_a_figure_stopped_mid_write_leaves_the_one_before_it(tmp_path):
    """Figures are written atomically: a write that fails half-way (here the SVG, after
    some bytes) leaves the previous SVG as it was and no temporary file, and the figure
    is closed; the PNG written before it is the new one, whole."""
    import matplotlib.pyplot as plt

    def figure(y: float):
        fig, ax = plt.subplots()
        ax.plot([0.0, 1.0], [0.0, y], label="line")
        ax.set(xlabel="x, m", ylabel="y, m")
        ax.legend()
        return fig

    stem = tmp_path / "fig"
    figstyle.save(figure(1.0), stem)
    old_png, old_svg = (stem.with_suffix(e).read_bytes() for e in (".png", ".svg"))
    fig = figure(2.0)
    draw = fig.savefig

    def half_then_fail(path, *args, **kwargs):
        if kwargs.get("format") == "svg":
            Path(path).write_bytes(b"<svg")  # part of a file, then the write stops
            raise OSError("disk full")
        return draw(path, *args, **kwargs)

    fig.savefig = half_then_fail
    with pytest.raises(OSError, match="disk full"):
        figstyle.save(fig, stem)
    assert stem.with_suffix(".svg").read_bytes() == old_svg
    new_png = stem.with_suffix(".png").read_bytes()
    assert new_png != old_png and new_png.startswith(b"\x89PNG")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png", "fig.svg"]
    assert not plt.fignum_exists(fig.number)


def test_a_figure_laid_out_once_is_written_as_savefig_writes_it(tmp_path, monkeypatch):
    """``figstyle.save`` lays a constrained-layout figure out once and drops the engine
    (savefig drew each format twice): the PNG and SVG are byte for byte what ``savefig``
    writes when it lays the figure out for the PNG and the SVG keeps those positions,
    here with a log axis, a 3-D panel, a figure legend below the panels and a title above
    them."""
    import matplotlib.pyplot as plt

    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")  # the SVG's date
    monkeypatch.setitem(plt.rcParams, "svg.hashsalt", "same ids")

    def figure():
        fig, axes = figstyle.figure(2, 2)
        axes[1, 1].remove()
        axes[1, 1] = fig.add_subplot(2, 2, 4, projection="3d")  # laid out as it is drawn
        for i, ax in enumerate(axes.flat):
            ax.plot([1.0, 10.0, 300.0], [0.0, 0.5 + i, 1.0], label=f"curve {i}")
            ax.set(xlabel="miss distance, m", ylabel="fraction of runs", title=f"panel {i}")
        axes[0, 1].set_xscale("log")
        figstyle.figure_legend(fig, axes.flat)
        fig.suptitle("a title over the panels")
        figstyle.plain_log_labels(fig)
        return fig

    ref = figure()  # laid out by the PNG's savefig, the SVG in the same positions
    ref.savefig(tmp_path / "ref.png", format="png", dpi=figstyle.DPI)
    ref.set_layout_engine("none")
    ref.savefig(tmp_path / "ref.svg", format="svg", dpi=figstyle.DPI)
    plt.close(ref)
    figstyle.save(figure(), tmp_path / "ours")
    for ext in ("png", "svg"):
        ours, theirs = ((tmp_path / f"{n}.{ext}").read_bytes() for n in ("ours", "ref"))
        assert ours == theirs, ext


def test_crowded_cdf_puts_one_legend_below_the_panels():
    """Eight estimators x four noises: the legend leaves the axes (it hid the curves)."""
    from kalman_vs_infoset.experiments import plots

    rng = np.random.default_rng(0)
    rows = [{"estimator": e, "noise": n, "miss_m": m, "fuel_mps": 100 + m}
            for e in registry.names("intercept") for n in ("random", "game", "bias", "targeted")
            for m in rng.uniform(0.1, 10, 5)]  # fmt: skip
    fig = plots.cdf_figure(pd.DataFrame(rows), ["estimator", "noise"], "many", {})
    assert figure_problems(fig) == []
    assert len(fig.legends) == 1 and all(ax.get_legend() is None for ax in fig.axes)
    few = plots.cdf_figure(pd.DataFrame(rows[:10]), ["estimator", "noise"], "few", {})
    assert not few.legends and few.axes[0].get_legend() is not None


def test_a_legend_below_the_panels_leaves_them_their_height():
    """Fig. 5's figure: four curves and three marks a panel put the legend below both
    panels; the figure grows by its rows, counted from every curve and mark (the count
    took two marks a panel, and the panels lost 6 % of their height)."""
    from kalman_vs_infoset.experiments import plots

    rng = np.random.default_rng(0)
    rows = [{"variant": v, "noise": n, "miss_m": m, "fuel_mps": 100 + 20 * m, "status": "ok"}
            for v in ("bearing only", "bearing + range") for n in ("random", "game")
            for m in rng.uniform(0.1, 10, 20)]  # fmt: skip
    paper = ("paper Fig. 3, random errors", "paper Fig. 3, game errors")
    marks = {
        "miss_m": [(4.3, paper[0]), (9.5, paper[1]), (1.15, "bearing-limited miss scale")],
        "fuel_mps": [(244.7, paper[0]), (521.7, paper[1]), (44.8, "perfect information")],
    }

    def panel_height_in(references) -> float:
        fig = plots.cdf_figure(pd.DataFrame(rows), ["variant", "noise"], "t", references)
        fig.canvas.draw()
        return fig.axes[0].get_window_extent().height / fig.dpi

    crowded = plots.cdf_figure(pd.DataFrame(rows), ["variant", "noise"], "t", marks)
    assert len(crowded.legends) == 1  # below the panels
    assert panel_height_in(marks) >= 0.97 * panel_height_in(None)


def _fig8_peaks_on_the_formulas_side(fig8) -> None:
    # seed 001 eq. (24): the plant's turns reach each limit on the side the formula says
    for angle, (torque, momentum) in fig8["peaks"].items():
        assert (torque >= 0.999) == (float(angle) >= fig8["phi10_deg"]), angle
        assert (momentum >= 0.999) == (float(angle) >= fig8["phi20_deg"]), angle


def _inertia_signs(signs) -> None:
    assert {"[-,-,-] standard", "[+,+,+] entries"} <= set(signs["Z_energy"])
    # seed 000: the 300-s error is set by f1, f2, not by the inertia's signs
    angles = signs["angle_at_300s_deg"]
    assert set(angles) == set(signs["Z_energy"])
    assert max(angles.values()) - min(angles.values()) < 1e-3


#: checks of the published numbers of ``paper_figures.json``, by key
PAPER_NUMBERS = {
    "kp_fig3": lambda n: n["paper_miss_fuel"]["random"] == [4.3, 244.7],
    "resurs": lambda n: n["Z_paper"] == {"energy": 2150.0, "euler": 11200.0},
    "akimov_fig8": lambda n: _fig8_peaks_on_the_formulas_side(n) is None,
    "akimov_fig9": lambda n: n["peak_torque_ratio"] < 1.0,  # seed Fig. 9: unconstrained
    "lqr_lyapunov": lambda n: n["monotone"],  # seed 002: V never increases
    "resurs_inertia_signs": lambda n: _inertia_signs(n) is None,
    "resurs_noisy": lambda n: n["truth_inside_bound"],
    "kp_fig5": lambda n: set(n["fig3_engagement"]) == {"random", "game"},
}
#: the paper figures' groups in three parts of similar cost (about 16 CPU-s each), one
#: test each, so that two xdist workers share them; with the numbers each part checks
PAPER_PARTS = {
    ("kp_fig3", "kp_fig4", "lqr"): {"kp_fig3", "lqr_lyapunov"},
    ("kp_fig5", "resurs", "gyrostat"): {"kp_fig5", "resurs"},
    ("resurs_more", "akimov", "akimov_more"): {
        "resurs_inertia_signs", "resurs_noisy", "akimov_fig8", "akimov_fig9",
    },
}  # fmt: skip


def test_paper_figures_parts_cover_every_group_and_number(tmp_path, capsys, monkeypatch):
    """The parts below draw every group once and check every number; and without
    ``--only`` the command draws every group, in order (fakes instead of the groups)."""
    from kalman_vs_infoset.experiments import cmd_paper_figures as pf

    parts = [g for part in PAPER_PARTS for g in part]
    assert sorted(parts) == sorted(pf.GROUPS) and set(pf.FIGURES.values()) <= set(pf.GROUPS)
    assert set().union(*PAPER_PARTS.values()) == set(PAPER_NUMBERS)
    drawn: list[str] = []
    fakes = {g: (lambda ctx, g=g: drawn.append(g) or {g: 1}) for g in pf.GROUPS}
    figures = pf.FIGURES
    monkeypatch.setattr(pf, "_tables", lambda: (figures, fakes))  # the tables run() reads
    out = tmp_path / "fig"
    assert main(["paper-figures", "--out", str(out), "--runs", "1", "--quick", "--json"]) == 0
    assert drawn == list(fakes)
    numbers = json.loads((out / "paper_figures.json").read_text())["numbers"]
    assert numbers == {g: 1 for g in fakes}


@pytest.mark.parametrize("part", list(PAPER_PARTS), ids=lambda p: "+".join(p))
def test_paper_figures_writes_every_listed_file(part, tmp_path, capsys, checked):
    """Every paper figure of a part of the groups (reduced count and coarser steps), PNG
    and SVG, checked, and the published numbers they report."""
    from kalman_vs_infoset.experiments.cmd_paper_figures import FIGURES

    out = tmp_path / "fig"
    # a group by the name of one of its figures ("resurs" and "akimov" name two groups)
    only = ",".join(next(n for n, g in FIGURES.items() if g == group) for group in part)
    argv = ["paper-figures", "--out", str(out), "--runs", "1", "--quick", "--only", only]
    assert main([*argv, "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    names = {name for name, group in FIGURES.items() if group in part}
    for name in names:
        for ext in ("png", "svg"):
            assert (out / f"{name}.{ext}").is_file(), f"{name}.{ext}"
    assert names == set(result["figures"])
    assert {f.rsplit("/", 1)[-1] for f in checked} == names
    numbers = json.loads((out / "paper_figures.json").read_text())["numbers"]
    assert PAPER_PARTS[part] <= set(numbers)
    for key in PAPER_PARTS[part]:
        assert PAPER_NUMBERS[key](numbers[key]), key


def test_a_plug_in_belief_with_the_interface_only_is_described_without_its_box():
    """A plug-in belief that has only ``Belief``'s methods (here a node set wrapped, its
    own range methods and sizes not passed on) is traced: the node set refuses a
    coordinate function (``TypeError``, which the interface allows), so the bounding box
    is NaN, as are the sizes, and every other field is the unwrapped belief's (it raised
    before)."""
    from kalman_vs_infoset.estim.base import Belief
    from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator

    class Wrapped(Belief):
        def __init__(self, inner):
            self.inner = inner

        status = property(lambda self: self.inner.status)
        contradictions = property(lambda self: self.inner.contradictions)
        is_empty = property(lambda self: self.inner.is_empty)

        def centre(self):
            return self.inner.centre()

        def extremes(self, fn):
            return self.inner.extremes(fn)

        def attained(self, fn):
            return self.inner.attained(fn)

        def contains(self, state):
            return self.inner.contains(state)

    model = ChannelModel()
    est = NodeSetEstimator(model)
    inner = est.initial(lateral_m=(-1e3, 1e3), lateral_vel_mps=(-100.0, 100.0), x_m=(7e5, 9e5))
    plain, wrapped = describe_channel(inner, model), describe_channel(Wrapped(inner), model)
    box = {f"{q}_{end}_{u}" for q, u in (("alpha", "rad"), ("omega", "radps"), ("x", "m"))
           for end in ("lo", "hi")}  # fmt: skip
    assert all(np.isnan(wrapped[k]) for k in box) and all(np.isfinite(plain[k]) for k in box)
    own = set(inner.trace_fields())  # sizes the wrapper does not pass on either
    assert all(np.isnan(wrapped[k]) for k in own)
    for key in set(plain) - box - own:
        assert wrapped[key] == plain[key] or (np.isnan(plain[key]) and np.isnan(wrapped[key])), key


def test_a_cdf_of_more_than_six_curves_keeps_its_legend_below_the_panels():
    """Nine curves (three estimators x three noises) had their legend inside the fuel
    panel, over two filters' curves; above six it goes below both panels."""
    import pandas as pd
    from kalman_vs_infoset.experiments import plots

    def figure(n_est: int):
        rows = [{"estimator": f"e{i}", "noise": n, "miss_m": 1.0 + j, "fuel_mps": 100.0 + j,
                 "status": "ok"} for i in range(n_est) for n in ("random", "game", "bias")
                for j in range(3)]  # fmt: skip
        return plots.cdf_figure(pd.DataFrame(rows), ["estimator", "noise"], "t")

    nine, six = figure(3), figure(2)
    assert nine.legends and not any(ax.get_legend() for ax in nine.axes)
    assert not six.legends and all(ax.get_legend() for ax in six.axes)


def test_values_close_together_are_ticked_without_an_offset(tmp_path):
    """Runs whose energies differ in the sixth digit (1.0680e-2 ... 1.0689e-2): matplotlib
    wrote the ticks as an offset, "1e-6+1.068e-2", below the axis's end, over its label;
    the ticks now say their values and no offset is drawn."""
    fs = figstyle
    fs.setup()
    fig, ax = fs.plt.subplots(figsize=(5.0, 3.5))
    x = 1.068e-2 + np.array([0.5, 3.8, 4.2, 8.3, 8.8]) * 1e-9 * 1e3
    ax.ecdf(x)
    ax.set_xlabel("energy index sum M^T M dt, N^2 m^2 s")
    fig.canvas.draw()
    assert ax.xaxis.get_offset_text().get_text() == ""
    labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
    assert labels and all(float(t.replace("\u2212", "-")) > 0.01 for t in labels)
    fs.plt.close(fig)


@pytest.mark.parametrize("width_in", [15.0, 7.5, 6.0, 3.0])
def test_long_tick_labels_of_a_narrow_panel_do_not_run_into_each_other(tmp_path, width_in):
    """Without an offset, the energies of a 1x3 attitude CDF (0.0106805 .. 0.0106838)
    were eight labels of nine characters on a third of the figure, overlapping. Saved,
    at any figure width, the labels' drawn boxes (the renderer's, not the estimate that
    thinned them) are apart and at least one is drawn; a panel whose labels fit keeps
    matplotlib's own ticks."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fs = figstyle
    fig, grid = fs.figure(1, 3, size=(width_in, 4.4))
    energy, settle, _ = grid[0]
    energy.ecdf(0.0106805 + np.array([0.0, 3.3e-6]))
    settle.ecdf([40.83, 40.91])
    before = list(settle.get_xticks())
    for ax in grid[0]:
        ax.set_xlabel("x, -")
        ax.set_ylabel("y, -")
    fs.save(fig, tmp_path / "ticks", formats=("png",))
    renderer = FigureCanvasAgg(fig).get_renderer()  # (save closed the figure's canvas)
    fig.draw(renderer)  # as saved: the layout was fixed and its engine removed
    for ax in (energy, settle):
        lo, hi = sorted(ax.get_xlim())
        shown = [t for t in ax.get_xticklabels()
                 if t.get_text() and lo <= t.get_position()[0] <= hi]  # fmt: skip
        boxes = sorted((t.get_window_extent(renderer) for t in shown), key=lambda b: b.x0)
        assert boxes
        assert all(a.x1 < b.x0 for a, b in zip(boxes, boxes[1:], strict=False)), [
            t.get_text() for t in shown
        ]
    if width_in == 15.0:
        assert list(settle.get_xticks()) == before and len(before) >= 8
