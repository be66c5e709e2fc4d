"""Every attitude run's row has its loop's declared result columns
(:meth:`AttitudeLoop.columns`), and a table of failed runs gets them as NaN: selecting
``settle_time_s`` of a table whose every run failed does not raise KeyError. (The
Lyapunov, gyrodine and gyrostat loops' rows are checked against their declarations in
test_attitude_divergence.py, beside runs those tests make anyway.)"""

from __future__ import annotations

from dataclasses import replace

from harness_texts import JOB_COLUMNS
from kalman_vs_infoset.experiments import attitude_rw

from kalman_vs_infoset import api

SHORT = {"duration_s": 2.0}


def test_a_pd_run_s_row_has_exactly_the_declared_columns():
    df = api.run_attitude("smallsat_rw", noise="random", estimator="box", runs=1,
                          simulation=SHORT)  # fmt: skip
    assert df["status"].tolist() == ["ok"]
    assert set(df.columns) - JOB_COLUMNS == set(attitude_rw.LOOP.columns("pd"))


def test_a_table_of_failed_attitude_runs_has_the_result_columns(monkeypatch):
    def fails(*args, **kwargs):
        raise ArithmeticError("every run fails")

    monkeypatch.setattr(attitude_rw, "LOOP", replace(attitude_rw.LOOP, task=fails))
    df = api.run_attitude("smallsat_rw", noise="random", estimator="box", runs=2,
                          simulation=SHORT)  # fmt: skip
    assert (df["status"] == "failed").all()
    assert set(attitude_rw.LOOP.columns("pd")) <= set(df.columns)
    assert df["settle_time_s"].isna().all() and df["truth_outside"].isna().all()
