"""Operation: progress where it can be seen (a bar, or log lines in a log), the install
hint for the cluster extra, and the CDFs drawn by ``Axes.ecdf`` exactly as before."""

import io
import logging
import sys

import matplotlib
import numpy as np
import pytest
from kalman_vs_infoset.experiments import executors, plots, progress
from kalman_vs_infoset.experiments.errors import InputError

matplotlib.use("Agg")


def test_cdf_curve_is_the_empirical_cdf_of_the_finite_values():
    """The curve steps from 0 at the smallest value up by 1/n at each value (an
    independent construction: sorted values, ``k/n``)."""
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(0)
    v = rng.lognormal(size=37)
    v[5] = v[6]  # a tie
    fig, ax = plt.subplots()
    plots._cdf(ax, v, "a", color="k")
    (line,) = ax.lines
    finite = np.sort(v)
    n = len(finite)
    assert line.get_drawstyle() == "steps-post"
    np.testing.assert_array_equal(line.get_xdata(), np.concatenate([[finite[0]], finite]))
    np.testing.assert_array_equal(line.get_ydata(), np.arange(n + 1) / n)
    plt.close(fig)


def test_cdf_of_runs_that_never_settled_ends_at_the_share_that_did():
    """``+inf`` (never settled) is larger than every time: with 2 of 37 runs unsettled the
    curve climbs by 1/37 a settled run and ends at 35/37, not at 1; NaN is left out of
    both counts (sorted values, ``k/n``, built independently)."""
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(1)
    v = rng.lognormal(size=38)
    v[3], v[8], v[11] = np.inf, np.inf, np.nan
    fig, ax = plt.subplots()
    plots._cdf(ax, v, "a", color="k")
    (line,) = ax.lines
    finite = np.sort(v[np.isfinite(v)])
    assert len(finite) == 35 and line.get_drawstyle() == "steps-post"
    np.testing.assert_array_equal(line.get_xdata(), np.concatenate([[finite[0]], finite]))
    np.testing.assert_allclose(line.get_ydata(), np.arange(36) / 37, rtol=0, atol=1e-15)
    assert line.get_ydata()[-1] < 1.0
    plt.close(fig)


def test_cdf_figure_labels_say_which_runs_each_curve_leaves_out(monkeypatch, tmp_path):
    """A curve is drawn over the runs with a value; its label counts those and names the
    failed runs and the NaN values it leaves out (the label said n=12 over a curve of
    6 or 9 runs that reached 1). A group whose every run failed keeps its legend
    entry. The attitude figure labels its curves alike."""
    import pandas as pd
    from kalman_vs_infoset.experiments.attitude_est import write_figure

    rng = np.random.default_rng(2)
    rows = pd.DataFrame(
        {"estimator": ["ekf"] * 12 + ["ukf"] * 12 + ["pf"] * 3, "noise": "game",
         "status": "ok", "miss_m": rng.lognormal(size=27), "fuel_mps": rng.uniform(size=27)}
    )  # fmt: skip
    rows.loc[:5, "status"] = "failed"  # 6 of ekf's runs
    rows.loc[rows.index[12:15], "miss_m"] = np.nan  # 3 of ukf's misses
    rows.loc[rows.index[24:], "status"] = "failed"  # every pf run
    fig = plots.cdf_figure(rows, ["estimator", "noise"], "t", {})
    miss = {line.get_label(): line for line in fig.axes[0].lines}
    assert set(miss) == {
        "EKF / game (n=6, 6 failed)",
        "UKF / game (n=9, 3 without a value)",
        "particle filter / game (n=0, 3 failed)",
    }
    ekf = miss["EKF / game (n=6, 6 failed)"]
    assert len(ekf.get_xdata()) == 7 and ekf.get_ydata()[1] == 1 / 6  # a step per run
    assert len(miss["particle filter / game (n=0, 3 failed)"].get_xdata()) == 0
    fuel = {line.get_label() for line in fig.axes[1].lines}
    assert "UKF / game (n=12)" in fuel

    att = pd.DataFrame(
        {"controller": "pd", "estimator": "box", "noise": "random",
         "status": ["ok"] * 4 + ["failed"], "settle_time_s": [1.0, 2.0, np.inf, 3.0, np.nan],
         "energy_N2m2s": 1.0, "final_angle_deg": 0.1}
    )  # fmt: skip
    drawn = []
    monkeypatch.setattr(plots, "save", lambda fig, stem: drawn.append(fig) or [])
    write_figure(tmp_path, "s", att)
    (settle, *_) = drawn[0].axes
    labels = [line.get_label() for line in settle.lines]
    assert labels == ["pd / guaranteed box / random (n=4, 1 failed)"]
    assert settle.lines[0].get_ydata()[-1] == 0.75  # one of the four never settled


class _Pipe(io.StringIO):
    def isatty(self) -> bool:
        return False


def test_progress_goes_to_log_lines_when_stderr_is_not_a_terminal(monkeypatch):
    err = _Pipe()
    monkeypatch.setattr(sys, "stderr", err)
    progress.configure_logging()
    progress.configure_logging()  # once: no second handler
    assert sum(isinstance(h, progress._Stderr) for h in progress.LOG.handlers) == 1
    bar = progress.progress_bar(4, 1, "kp_fig5 infoset-random", every_s=0.0)
    assert not hasattr(bar, "disable")  # not a tqdm bar
    for _ in range(3):
        bar.update(1)
    bar.close()
    lines = err.getvalue().splitlines()
    assert lines[0].startswith("kvi: kp_fig5 infoset-random: 2/4 runs, ~")
    assert lines[2].startswith("kvi: kp_fig5 infoset-random: 4/4 runs")
    assert lines[-1].endswith(" s)") and len(lines) == 4
    err.truncate(0)
    off = progress.progress_bar(4, 0, "x", enabled=False)
    off.update(4)
    off.close()
    assert err.getvalue() == ""


def test_progress_is_a_tqdm_auto_bar_on_a_terminal(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr(sys, "stderr", Tty())
    bar = progress.progress_bar(3, 0, "d")
    from tqdm.auto import tqdm

    assert isinstance(bar, tqdm) and not bar.disable
    bar.close()


def test_library_use_logs_nothing_unless_logging_is_configured(monkeypatch, caplog):
    monkeypatch.setattr(sys, "stderr", _Pipe())
    with caplog.at_level(logging.INFO, logger="kalman_vs_infoset"):
        bar = progress.progress_bar(2, 0, "job", every_s=0.0)
        bar.update(2)
        bar.close()
    assert any("job: 2/2 runs" in r.getMessage() for r in caplog.records)


def test_the_cluster_hint_names_the_package(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # not installed
    with pytest.raises(InputError, match=r"pip install 'kalman-vs-infoset\[cluster\]'"):
        with executors.make_executor(scheduler="tcp://127.0.0.1:1"):
            pass


def test_a_first_run_compile_is_announced_once(monkeypatch, tmp_path, caplog):
    monkeypatch.setattr(progress, "_announced", False)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # an empty cache
    assert progress.compiled_kernels_cached() is False
    with caplog.at_level(logging.INFO, logger="kalman_vs_infoset"):
        for _ in range(2):
            progress.progress_bar(1, 0, "job").close()
    assert [r.getMessage() for r in caplog.records if "compiling" in r.getMessage()] == [
        "first run: compiling the estimators' kernels (about a minute, once)"
    ]
    from kalman_vs_infoset._jit import kernel_files

    (tmp_path / "x").mkdir()
    stems = sorted({f.stem for f in kernel_files()})
    assert {"_kernels", "_geometry", "_kepler"} <= set(stems)
    for stem in stems[1:]:
        (tmp_path / "x" / f"{stem}.f-1.py311.nbi").write_bytes(b"")
    assert progress.compiled_kernels_cached() is False  # one kernel module missing
    (tmp_path / "x" / f"{stems[0]}.f-1.py311.nbi").write_bytes(b"")
    assert progress.compiled_kernels_cached() is True


def test_the_cache_guess_finds_kernels_beside_their_sources_and_sees_an_edit(monkeypatch, tmp_path):
    """Without NUMBA_CACHE_DIR numba caches in ``__pycache__`` beside each kernel's own
    source (sub-packages too): every kernel source needs its index there, written after
    the last edit of any kernel source (the cache is stamped with all of them). Before,
    only the ``estim`` folder's own ``__pycache__`` was looked at, so a library user's
    progress bar announced a first-run compile on every run."""
    import os

    from kalman_vs_infoset import _jit

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    srcs = [tmp_path / "estim" / "a" / "_kernels.py", tmp_path / "guidance" / "_kepler.py"]
    for src in srcs:
        (src.parent / "__pycache__").mkdir(parents=True)
        src.write_text("@njit\n")
    monkeypatch.setattr(_jit, "kernel_files", lambda: tuple(srcs))
    index = [s.parent / "__pycache__" / f"{s.stem}.f-3.py311.nbi" for s in srcs]
    index[0].write_bytes(b"")
    assert progress.compiled_kernels_cached() is False
    index[1].write_bytes(b"")
    assert progress.compiled_kernels_cached() is True
    later = index[1].stat().st_mtime + 5.0
    os.utime(srcs[0], (later, later))  # a kernel edited after the cache was written
    assert progress.compiled_kernels_cached() is False


def test_kvi_version_names_the_installed_package(capsys):
    from kalman_vs_infoset.experiments.cli import main

    import kalman_vs_infoset

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"kvi {kalman_vs_infoset.__version__}"


def _modules_a_run_imports(name: str, noise: str) -> list[str]:
    """In a pool worker: the modules that one engagement imports (none are expected:
    the pool's parent loaded them, :func:`executors.warm_kernels`)."""
    from kalman_vs_infoset.experiments.intercept_runs import timed_engagement
    from kalman_vs_infoset.experiments.runner import run_seed
    from kalman_vs_infoset.experiments.scenario import load_scenario, scenario_folder

    sc = load_scenario(scenario_folder(None) / f"{name}.toml")
    before = set(sys.modules)
    row = timed_engagement(sc, "infoset", noise, run_seed(1, 0))
    assert row["status"] == "ok", row
    return sorted(set(sys.modules) - before)


@pytest.mark.parametrize("name, noise", [("kp_fig5_range", "random"), ("kp_fig5", "game")])
def test_a_forked_worker_imports_nothing_on_its_first_run(name, noise):
    """Each worker of a pool inherits the libraries a run needs: importing them on its
    first run cost every worker of every pool 0.3 CPU-s (scipy.optimize), about 4 % of
    ``kvi fig5``. Runs in a forked worker, as the runner's are."""
    import multiprocessing

    if multiprocessing.get_start_method() != "fork":
        pytest.skip("the workers inherit the parent's modules only when forked")
    with executors.make_executor(1) as pool:
        assert pool.submit(_modules_a_run_imports, name, noise).result() == []


def test_a_pool_s_parent_freezes_its_objects_while_the_pool_lives():
    """Python's advice for forked workers (``gc.freeze`` before the fork): the parent's
    objects sit in the permanent generation while the pool lives, so a worker's
    collections do not write to them; the parent collects them again afterwards."""
    import gc

    assert gc.get_freeze_count() == 0
    with executors.make_executor(1) as pool:
        frozen = gc.get_freeze_count()
        assert pool.submit(abs, -3).result() == 3
    assert frozen > 10_000 and gc.get_freeze_count() == 0
