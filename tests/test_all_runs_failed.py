"""A command whose every run failed (an error, a CPU or memory limit) says so and exits
1, with the failed rows saved: no traceback from the summaries, tables or plots that
have no successful run to show."""

from __future__ import annotations

import pytest
from harness_texts import run_cli as run
from kalman_vs_infoset.experiments import intercept_runs


def _always_fails(sc, est, noise, rng):
    raise ArithmeticError("every run fails")


@pytest.mark.parametrize(
    "command",
    [
        ["intercept", "--estimators", "ekf", "--noise", "random"],
        ["compare", "--estimators", "ekf,infoset", "--noise", "random"],
        ["sweep", "--estimators", "ekf", "--noise", "random", "--key",
         "guidance.max_impulse_mps", "--values", "[50, 60]"],
        ["adversaries", "--estimators", "ekf"],
        ["fig5", "--estimators", "ekf"],
    ],
    ids=lambda c: c[0],
)  # fmt: skip
def test_every_run_failed_is_reported_not_a_traceback(
    command, short, tmp_path, capsys, monkeypatch
):
    monkeypatch.setattr(intercept_runs, "run_engagement", _always_fails)
    name, *rest = command
    where = [] if name == "fig5" else [short]  # fig5 runs its bundled variants
    r = run(capsys, name, *where, "--runs", 2, "--workers", 1, "--no-progress",
            "--out", tmp_path / "out", *rest)  # fmt: skip
    assert "Traceback" not in r.stderr, r.stderr
    assert r.returncode == 1, r.stderr
    assert "runs failed" in r.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("to_folder", [False, True], ids=["in_memory", "out"])
def test_the_api_s_table_of_failed_runs_has_the_result_columns(short, tmp_path, monkeypatch,
                                                               to_folder):  # fmt: skip
    """``run_experiment`` returns the result columns even when no run gave any (NaN),
    so ``df["miss_m"]`` selects them instead of raising KeyError."""
    from kalman_vs_infoset.experiments.sim.intercept import EngagementResult

    from kalman_vs_infoset.api import run_experiment

    monkeypatch.setattr(intercept_runs, "run_engagement", _always_fails)
    out = tmp_path / "out" if to_folder else None
    df = run_experiment(short, "ekf", "random", runs=2, out=out)
    assert (df["status"] == "failed").all()
    assert set(EngagementResult.columns()) <= set(df.columns)
    assert df["miss_m"].isna().all() and df["fuel_mps"].isna().all()
    assert "miss_m" in EngagementResult.columns() and "x0_km" in EngagementResult.columns()


def test_the_declared_intercept_columns_are_a_finished_run_s_row(short):
    """``EngagementResult.columns()`` names exactly what a finished run's row holds
    (beside the estimator's own ``extras``): the columns a failed table is given."""
    import numpy as np
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.intercept import EngagementResult, run_engagement

    res = run_engagement(load_scenario(short), "infoset", "random", np.random.default_rng(0))
    row = res.as_row()
    assert set(row) - {k for k, _ in res.extras} == set(EngagementResult.columns())
