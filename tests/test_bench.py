"""``kvi bench`` (docs/models.md §3.1): every estimator's step, the engagement and the
throughput side by side, in CPU time; its first-run compilation on an empty cache."""

import json
from pathlib import Path

import numpy as np
import pytest
from docs_numbers import ROOT
from harness_texts import cli_inproc
from kalman_vs_infoset.estim import registry


def test_bench_reports_every_field_side_by_side(capsys):
    """`bench --json` (docs/models.md §3.1): all costs measured in one process, in CPU time
    (``--quick``: a few steps, short approaches, two Monte Carlo runs)."""
    r = cli_inproc(capsys, "bench", "--json", "--quick")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    for key in (
        "infoset_step_us",
        "ekf_step_us",
        "ukf_step_us",
        "engagement_ms",
        "engagement_random_ms",
        "engagement_in_ukf_steps",
        "engagement_random_in_ukf_steps",
        "runs_per_s",
        "runs_per_s_2",
        "speedup_2_workers",
        "infoset_to_ukf_ratio",
        "hinf_step_us",
        "pf_step_us",
    ):
        assert out[key] > 0, key

    names = registry.names("intercept")  # every registered estimator, side by side
    assert set(out["step_us"]) == set(names)
    assert all(out[f"{n}_step_us"] == out["step_us"][n] > 0 for n in names)
    assert out["machine"]["cpus"] >= 1
    # the whole approach (to the blind range) whatever --steps says
    whole, n_steps = out["whole_approach_step_us"], out["whole_approach_steps"]
    assert set(whole) == {"infoset", "ukf"} and all(whole[n] > 0 for n in whole)
    assert n_steps["infoset"] == n_steps["ukf"] > 5
    assert out["whole_approach_ratio"] == whole["infoset"] / whole["ukf"]
    # its last tenth of steps and the steps before them (--quick: one pass, so the mean
    # over all steps is the two parts' weighted mean)
    share, tail = out["whole_approach_tail_share"], out["whole_approach_tail_steps"]
    head = out["whole_approach_head_step_us"]
    for n in ("infoset", "ukf"):
        assert tail[n] == round(0.1 * n_steps[n]) and 0.0 < share[n] < 1.0
        assert head[n] * (n_steps[n] - tail[n]) == pytest.approx(
            (1.0 - share[n]) * whole[n] * n_steps[n]
        )
    assert out["whole_approach_head_ratio"] == head["infoset"] / head["ukf"]
    # the set's nodes made a step over that approach (the UKF has none)
    made = out["whole_approach_nodes_made"]
    assert made["head"] >= 0.0 and made["tail"] >= 0.0
    assert 0.0 <= made["tail_gone_in_a_step"] <= 1.0
    assert out["engagement_in_ukf_steps"] == pytest.approx(
        out["engagement_ms"] * 1e3 / out["ukf_step_us"]
    )
    # the cost exponent: a least-squares slope over approaches twice and four times as long
    steps, cost = np.array(out["cost_steps"]), np.array(out["cost_ms"])
    assert np.allclose(steps[1:] / steps[:-1], 2.0, rtol=0.1) and (cost > 0).all()
    slope = np.polyfit(np.log(steps), np.log(cost), 1)[0]
    assert out["cost_exponent"] == pytest.approx(slope)
    # the node set's slices: a mean vertex count per approach, at most the largest
    mean_v, max_v = out["cost_mean_vertices"], out["cost_max_vertices"]
    assert len(mean_v) == len(max_v) == len(steps)
    assert all(3.0 <= m <= big for m, big in zip(mean_v, max_v, strict=True))
    # one run a task against two (--quick: 2 runs), on 2 workers
    assert out["runs_per_cpu_s_by_chunk"]["1"] == out["runs_per_cpu_s"]["2"]
    assert set(out["runs_per_cpu_s_by_chunk"]) == {"1", "2"}
    assert out["runs_per_cpu_s_by_chunk"]["2"] > 0
    for workers in ("1", "2"):
        assert out["runs_per_cpu_s"][workers] > 0
        assert 10.0 < out["worker_peak_rss_mb"][workers] < 1e5
    assert out["first_run_compile_s"] is None  # --quick skips the fresh-cache run
    # start-up in a fresh interpreter (--quick: the top level and one command)
    assert set(out["help_cpu_s"]) == {"(none)", "intercept"}
    assert all(v > 0 for v in out["help_cpu_s"].values())
    assert out["help_cpu_s_max"] == max(out["help_cpu_s"].values())


def test_bench_counts_nodes_only_of_a_belief_with_nodes():
    """``whole_approach_nodes_made`` is the node set's: a filter's belief has none."""
    from kalman_vs_infoset.experiments.cmd_bench import approach_nodes
    from kalman_vs_infoset.experiments.scenario import load_scenario

    fig3 = load_scenario(str(ROOT / "data/scenarios/kp_fig3.toml"))
    assert approach_nodes("ukf", fig3, 4.0) is None
    made = approach_nodes("infoset", fig3, 4.0)
    assert made is not None and made["head"] + made["tail"] > 0.0


def test_bench_first_run_compiles_on_an_empty_cache(tmp_path):
    """The first-run measurement runs its code in a fresh process on an empty numba
    cache: a tiny kernel's compilation is seen, though it was cached before."""
    from kalman_vs_infoset.experiments.bench_process import first_run_compile

    (tmp_path / "tiny_kernel.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x + 1.0\n"
    )
    code = (
        "import json, sys\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        "from kalman_vs_infoset._numba_cache import CompileNotice\n"
        "n = CompileNotice('t').install()\n"
        "import tiny_kernel\n"
        "tiny_kernel.f(1.0)\n"
        "print(json.dumps({'compile_s': n.cpu_s, 'cpu_s': 1.0, 'kernels': n.kernels}))\n"
    )
    for _ in range(2):  # the second run finds no cache either
        out = first_run_compile(Path("unused"), code)
        assert out["kernels"] == 1 and out["compile_s"] > 0


def test_bench_steps_past_the_approach_or_a_diverged_set_are_not_timed():
    """`bench --steps 190` raised a traceback: a slab-family set diverged late in the
    unguided approach and its extremes were asked for. The timing stops there (and at
    the blind range), and says over how many steps it ran."""
    from kalman_vs_infoset.experiments.cmd_bench import step_cost_us
    from kalman_vs_infoset.experiments.scenario import load_scenario

    fig3 = load_scenario(str(ROOT / "data/scenarios/kp_fig3.toml"))
    model = fig3.channel_model()  # the bench's truth starts at 5801.3 km
    approach = int((5801.3e3 - model.eps_m) / model.e / fig3.model.dt_s)
    for name, (us, timed) in step_cost_us(
        registry.names("intercept"), fig3, 10 * approach, 1
    ).items():
        assert np.isfinite(us) and us > 0, name
        assert 0 < timed <= approach + 1, name


def test_cost_exponent_is_the_slope_of_the_median_passes_interleaved(monkeypatch):
    """Each approach's cost is the median of ``repeat`` passes, the step sizes taken in
    turn pass by pass (so a drift of the host's speed reaches all three alike), and the
    exponent is the least-squares slope through those medians (numpy's polyfit)."""
    from kalman_vs_infoset.experiments import cmd_bench

    dts = (1.0, 0.5, 0.25)
    steps = {1.0: 100, 0.5: 200, 0.25: 400}
    # pass k of dt: a cost with an outlier in one pass of each approach
    costs = {1.0: [0.05, 0.09, 0.04], 0.5: [0.11, 0.10, 0.30], 0.25: [0.31, 0.29, 0.33]}
    order: list[float] = []

    def fake_pass(name, sc, n, dt):
        order.append(dt)
        return costs[dt][sum(d == dt for d in order) - 1], steps[dt]

    monkeypatch.setattr(cmd_bench, "_approach_cpu_s", fake_pass)
    monkeypatch.setattr(cmd_bench, "_approach_vertices", lambda name, sc, dt: (10.0, 20))
    out = cmd_bench.cost_exponent(None, dts, repeat=3)
    assert order == list(dts) * 3
    assert out["cost_ms"] == pytest.approx([50.0, 110.0, 310.0])
    assert out["cost_ms_passes"] == [pytest.approx([c * 1e3 for c in costs[d]]) for d in dts]
    assert out["cost_steps"] == [100, 200, 400]
    slope = np.polyfit(np.log([100, 200, 400]), np.log([50.0, 110.0, 310.0]), 1)[0]
    assert out["cost_exponent"] == pytest.approx(slope)
    assert out["cost_mean_vertices"] == [10.0] * 3 and out["cost_max_vertices"] == [20] * 3


def test_the_estimators_passes_are_interleaved_and_each_cost_their_median(monkeypatch):
    """The step costs and the whole approach take the estimators in turn, pass by pass
    (a drift of the host's speed reaches them alike, as the ratios between them assume),
    and report each one's median pass."""
    from kalman_vs_infoset.experiments import cmd_bench

    order: list[str] = []
    cost = {"a": [3.0, 1.0, 2.0], "b": [5.0, 9.0, 4.0]}  # CPU-s of pass k

    def one_pass(name, sc, steps, dt):
        order.append(name)
        k = sum(n == name for n in order) - 1
        return np.full(10, cost[name][k] / 10), 0.0

    monkeypatch.setattr(cmd_bench, "_approach_step_cpu_s", one_pass)

    class Sc:
        class model:  # noqa: N801 (a stand-in for the scenario's table)
            dt_s = 0.5

    got = cmd_bench.step_cost_us(["a", "b"], Sc, 10, 3)
    assert order == ["a", "b"] * 3
    assert got == {"a": (pytest.approx(2e5), 10), "b": (pytest.approx(5e5), 10)}
    order.clear()
    whole = cmd_bench.whole_approach(["a", "b"], Sc, 0.5, 3)
    assert order == ["a", "b"] * 3
    assert whole["a"]["step_us"] == pytest.approx(2e5) and whole["b"]["steps"] == 10
    assert whole["b"]["tail_share"] == pytest.approx(0.1)


def test_a_plug_in_that_raises_is_left_out_of_the_timings_and_said(monkeypatch):
    """``kvi bench`` times every registered estimator: one plug-in raising at its first
    update ended the command with a traceback. It is left out, with its error, and the
    text says so; the ratios' reference and unit are never caught."""
    import sys

    from kalman_vs_infoset.experiments import cmd_bench
    from kalman_vs_infoset.experiments.scenario import load_scenario

    sys.path.insert(0, str(Path(__file__).parent))
    from toy_estimators import ToyOptions

    def broken(options, setting):
        est = ToyOptions().build(setting)
        monkeypatch.setattr(type(est), "update", lambda self, b, m: 1 / 0)
        return est

    registry.register("toy_broken", "intercept", ToyOptions, broken)
    try:
        fig3 = load_scenario(str(ROOT / "data/scenarios/kp_fig3.toml"))
        names, failed = cmd_bench._working(["ekf", "toy_broken"], fig3, ("ekf",))
        assert names == ["ekf"] and failed == {"toy_broken": "ZeroDivisionError: division by zero"}
        with pytest.raises(ZeroDivisionError):
            cmd_bench._working(["toy_broken"], fig3, ("toy_broken",))
    finally:
        registry.unregister("intercept", "toy_broken")


def test_options_given_count_with_quick_too():
    """``bench --quick --steps 3 --mc-runs 4`` timed 5 steps and 2 runs (``--quick``'s),
    silently; an option given now counts, and the others take the preview's or the
    full defaults."""
    from kalman_vs_infoset.experiments.cli import build_parser
    from kalman_vs_infoset.experiments.cmd_bench import counts

    def parsed(*args):
        return build_parser("bench").parse_args(["bench", *args])

    assert counts(parsed()) == (120, 3, 8)
    assert counts(parsed("--quick")) == (5, 1, 2)
    assert counts(parsed("--quick", "--steps", "3", "--mc-runs", "4")) == (3, 1, 4)
    assert counts(parsed("--quick", "--repeat", "2")) == (5, 2, 2)
    assert counts(parsed("--steps", "7")) == (7, 3, 8)
