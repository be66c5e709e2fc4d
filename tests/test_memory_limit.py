"""``--run-memory-limit-mb``: a run that allocates over its memory limit is recorded as
failed with the reason, the other runs go on, and the process's limit is restored.

The allocations are 2 GiB and never touched: with the limit they are refused at once,
without it (a broken limit) the test fails on the rows, not on the machine's memory.
"""

from __future__ import annotations

import resource
import sys

import numpy as np
import pandas as pd
import pytest
from harness_texts import one_line_error
from harness_texts import run_cli as run
from kalman_vs_infoset.experiments import intercept_runs
from kalman_vs_infoset.experiments.limits import RunLimits, limited
from numba import njit

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="RLIMIT_DATA counts memory maps on Linux"
)

BIG = 2**28  # float64 elements: 2 GiB


def _table(out) -> pd.DataFrame:
    (pq,) = out.rglob("*.parquet")
    return pd.read_parquet(pq).sort_values("run")


def _task(runs):
    rows = []
    for j in runs:
        if j == 1:
            np.empty(BIG)  # numpy's allocation
        if j == 2:
            _kernel_alloc(BIG)  # a compiled kernel's allocation (numba's runtime)
        rows.append((j, {"status": "ok", "error": ""}))
    return rows


@njit(cache=False)
def _kernel_alloc(n):
    return np.empty(n).shape[0]


def test_runs_over_the_limit_fail_one_by_one_and_the_limit_is_restored():
    _kernel_alloc(1)  # compiled outside the limit
    before = resource.getrlimit(resource.RLIMIT_DATA)
    pairs = limited(_task, RunLimits(memory_mb=64), [0, 1, 2, 3])
    assert resource.getrlimit(resource.RLIMIT_DATA) == before
    assert [j for j, _ in pairs] == [0, 1, 2, 3]
    assert [row["status"] for _, row in pairs] == ["ok", "failed", "failed", "ok"]
    for _, row in (pairs[1], pairs[2]):
        assert row["error"].startswith("MemoryError: over the memory limit of 64 MiB")
        assert "--run-memory-limit-mb" in row["error"]


def test_without_a_memory_limit_a_memory_error_is_the_runners_to_report():
    def task(runs):
        raise MemoryError

    with pytest.raises(MemoryError):
        limited(task, RunLimits(cpu_s=10.0), [0])


@pytest.mark.parametrize("workers", [1, 2], ids=["in-process", "pool-workers"])
def test_a_run_over_the_memory_limit_is_recorded_as_failed(
    short, tmp_path, capsys, monkeypatch, workers
):
    """Run 1 allocates 2 GiB: under a 256 MiB limit it fails with the reason, in this
    process and in pool workers (forked: they inherit the patched engagement); a rerun
    without the allocation completes it."""
    real = intercept_runs.run_engagement

    def hungry_run_1(sc, est, noise, rng):
        if rng.bit_generator.seed_seq.spawn_key == (1,):
            np.ones(BIG)
        return real(sc, est, noise, rng)

    monkeypatch.setattr(intercept_runs, "run_engagement", hungry_run_1)
    out = tmp_path / "out"
    args = ["intercept", short, "--runs", 3, "--workers", workers, "--no-progress",
            "--out", out, "--run-memory-limit-mb", 256]  # fmt: skip
    r = run(capsys, *args)
    assert r.returncode == 1, r.stderr
    df = _table(out)
    assert list(df["status"]) == ["ok", "failed", "ok"]
    assert "--run-memory-limit-mb" in df["error"].iloc[1]
    monkeypatch.setattr(intercept_runs, "run_engagement", real)
    assert run(capsys, *args).returncode == 0
    assert (_table(out)["status"] == "ok").all()


@pytest.mark.parametrize("value", ["0", "-5", "abc", "1e8", "nan"])
def test_a_bad_memory_limit_is_refused_in_one_line(short, capsys, value):
    r = run(capsys, "intercept", short, "--run-memory-limit-mb", value)
    assert one_line_error(r), r.stderr
    assert "--run-memory-limit-mb" in r.stderr


#: a fresh process's first BLAS calls (OpenBLAS allocates its work buffers then), under
#: a memory limit far below those buffers
_COLD_BLAS = """
import json, numpy as np
from kalman_vs_infoset.experiments.limits import RunLimits, limited
def task(runs):
    a = np.full((300, 300), 1e-3)
    np.linalg.cholesky(a @ a.T + np.eye(300))
    return [(j, {"status": "ok"}) for j in runs]
print(json.dumps(limited(task, RunLimits(memory_mb=2), [0])))
"""


def test_a_first_blas_call_under_the_limit_fails_the_run_not_the_process():
    """OpenBLAS does not raise when it cannot allocate its work buffers: it prints
    "Memory allocation still failed after 10 retries, giving up" and ends the process
    (`kvi intercept kp_fig5 --estimators pf --runs 1 --run-memory-limit-mb 20` ended so,
    leaving no table). The buffers are allocated before the limit is set, so the run
    meets the limit in its own allocation and is recorded as failed."""
    import json
    import subprocess

    proc = subprocess.run([sys.executable, "-c", _COLD_BLAS], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-500:]
    assert "OpenBLAS" not in proc.stderr
    ((run, row),) = json.loads(proc.stdout.strip().splitlines()[-1])
    assert run == 0 and row["status"] == "failed"
    assert row["error"].startswith("MemoryError: over the memory limit of 2 MiB")


def test_a_run_failing_otherwise_under_a_memory_limit_says_it_had_one():
    """An allocation over the limit inside a library can surface as another error (an
    ``OSError`` of an import, a ``SystemError``): a failed run's reason names the limit;
    a run that did not fail, or whose reason names it already, is left as it is."""

    def task(runs):
        return [
            (0, {"status": "failed", "error": "SystemError: error return without exception set"}),
            (1, {"status": "ok", "error": ""}),
            (2, {"status": "failed", "error": "MemoryError: ... (--run-memory-limit-mb): x"}),
        ]

    rows = dict(limited(task, RunLimits(memory_mb=64), [0, 1, 2]))
    assert rows[0]["error"] == (
        "SystemError: error return without exception set (under the memory limit of 64 MiB "
        "a run, --run-memory-limit-mb)"
    )
    assert rows[1] == {"status": "ok", "error": ""}
    assert rows[2]["error"] == "MemoryError: ... (--run-memory-limit-mb): x"
    assert dict(limited(task, RunLimits(cpu_s=5.0), [0, 1, 2]))[0]["error"].endswith("set")


def _exits_its_process(sc, estimator, noise, seed, runs):
    """A run that ends its process the way OpenBLAS does when an allocation fails (exit
    1, no exception). Module level: the pool's worker unpickles it."""
    import os

    os._exit(1)  # a library giving up, in the process that runs the run


def _command_with_an_exiting_run(scenario: str, out: str) -> None:
    """That run through the command, with a memory limit and one worker. Run in a forked
    child of the test process (as a separate process before, without its interpreter's
    start and imports): a run that ended the command's own process ends only the child."""
    from kalman_vs_infoset.experiments.cli import main

    intercept_runs._intercept_chunk = _exits_its_process  # in the child only
    code = main(["intercept", scenario, "--runs", "1", "--workers", "1", "--no-progress",
                 "--estimators", "ekf", "--run-memory-limit-mb", "500", "--out", out])  # fmt: skip
    print("command returned", code)


def test_a_memory_limited_run_never_crashes_the_command(tmp_path, capfd):
    """Under a limit too small for a run's first imports, CPython itself crashed within
    ``import scipy.stats`` (filterpy's): a segmentation fault of the whole command
    (``kvi compare ... --workers 1 --run-memory-limit-mb 2``). The libraries the runs
    import are loaded before the limit, and a limited run is run in a worker process,
    never in the command's: a run that ends its process ends a worker, which the command
    reports (exit status 1), and runs that fail under the limit name it."""
    import multiprocessing
    import subprocess

    from harness_texts import SHORT

    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    capfd.readouterr()  # the child's output only (its writes go to the captured fds)
    child = multiprocessing.get_context("fork").Process(
        target=_command_with_an_exiting_run, args=(str(scenario), str(tmp_path / "a"))
    )
    child.start()
    child.join(timeout=300)
    if child.is_alive():
        child.kill()
        pytest.fail("the command still runs after 300 s")
    out, err = capfd.readouterr()
    assert "command returned 1" in out, (child.exitcode, err[-2000:])
    assert "lost to a dead worker" in err.strip().splitlines()[-1]
    args = [sys.executable, "-m", "kalman_vs_infoset", "compare", str(scenario), "--runs", "1",
            "--workers", "1", "--no-progress", "--estimators", "ukf,box", "--noise", "random",
            "--run-memory-limit-mb", "2", "--out", str(tmp_path / "out")]  # fmt: skip
    proc = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert proc.returncode in (0, 1), (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr and "Segmentation" not in proc.stderr
    failed = [ln for ln in proc.stderr.splitlines() if " failed: " in ln]
    assert all(ln.endswith("--run-memory-limit-mb)") for ln in failed), failed
