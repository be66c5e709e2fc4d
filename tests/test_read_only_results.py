"""A complete results folder that the system refuses to write (a read-only mount, a
colleague's folder) is summarised again (docs/usage.md): the runs' tables are only
read, and what is derived from them (the combined table, CSV, Markdown, figures) is
skipped with one warning line each. ``compare``, ``fig5`` and ``attitude`` failed on
their combined table or figure with exit status 2 and printed no summary.

(The tests run as root in CI, where file modes do not stop writes: the refusal is the
system's answer, ``OSError(EROFS)``, given to every write.)"""

from __future__ import annotations

import errno
import json

import pytest
from harness_texts import cli_inproc
from kalman_vs_infoset.experiments import files, results, runner


def _refuse_every_write(monkeypatch) -> list[str]:
    tried: list[str] = []

    def refuse(path, write):
        tried.append(str(path))
        raise OSError(errno.EROFS, "Read-only file system", str(path))

    for module in (files, results, runner):  # each holds its own name for it
        monkeypatch.setattr(module, "atomic_write", refuse)
    return tried


def _untimed(stdout: str):
    """The command's JSON line without its timings (which differ run to run)."""

    def strip(value):
        if isinstance(value, dict):
            timing = ("wall_s", "cpu_s", "worker_peak_rss_mb")
            return {k: strip(v) for k, v in value.items() if k not in timing}
        return [strip(v) for v in value] if isinstance(value, list) else value

    return strip(json.loads(stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize(
    "command",
    [
        ["compare", "{short}", "--estimators", "infoset,ekf", "--noise", "random"],
        ["attitude", "{tiny_rw}", "--estimators", "box,ukf", "--noise", "random"],
    ],
    ids=lambda c: c[0],
)
def test_a_complete_read_only_folder_is_summarised_again(
    command, short, tiny_rw, tmp_path, capsys, monkeypatch
):
    args = [a.format(short=short, tiny_rw=tiny_rw) for a in command]
    out = tmp_path / "out"
    common = ["--runs", "2", "--workers", "1", "--no-progress", "--out", str(out), "--json"]
    first = cli_inproc(capsys, *args, *common)
    assert first.returncode == 0, first.stderr
    tried = _refuse_every_write(monkeypatch)
    again = cli_inproc(capsys, *args, *common)
    assert again.returncode == 0, again.stderr
    assert _untimed(again.stdout) == _untimed(first.stdout)  # the same summary
    warned = [line for line in again.stderr.splitlines() if "not written" in line]
    assert tried and len(warned) == len(tried)
    assert all(line.startswith("kvi: warning: ") for line in warned)
    assert all("(Read-only file system); the summary is printed" in line for line in warned)


def test_a_runs_table_that_cannot_be_saved_is_still_an_error(short, tmp_path, capsys, monkeypatch):
    """Only derived files are skipped: a run that cannot be saved stops the command
    (exit status 2, one line), never a silent loss."""
    _refuse_every_write(monkeypatch)
    r = cli_inproc(capsys, "intercept", short, "--runs", "1", "--workers", "1", "--no-progress",
                   "--out", tmp_path / "out")  # fmt: skip
    assert r.returncode == 2 and "Read-only file system" in r.stderr.strip().splitlines()[-1]


def test_plot_refuses_a_folder_it_cannot_write_before_drawing(tmp_path, capsys, monkeypatch):
    """``plot``'s only output is figures: a folder the system refuses (here every new
    file there: EROFS) is refused in one line, exit 2, before any figure is drawn (it
    printed the figures' names with exit status 0, none written); a file as ``--out`` is
    "not a directory", as for every command. (The traces are read and checked first, so
    that a refused trace leaves no folder behind: this one is a valid attitude trace.)"""
    import tempfile

    from harness_texts import small_attitude_trace

    trace = tmp_path / "a-trace.parquet"
    small_attitude_trace().to_parquet(trace)
    (tmp_path / "file").write_text("x")
    r = cli_inproc(capsys, "plot", trace, "--out", tmp_path / "file")
    assert r.returncode == 2 and r.stderr.strip().endswith("--out " + str(tmp_path / "file")
                                                           + ": not a directory")  # fmt: skip

    def refuse(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    for extra in (["--out", str(tmp_path / "figs")], []):  # given, or the traces' folder
        r = cli_inproc(capsys, "plot", trace, *extra)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert "cannot write there (Read-only file system)" in r.stderr
    assert list(tmp_path.glob("*.png")) == []


def test_a_figure_not_written_is_not_listed_unless_an_earlier_one_is_there(tmp_path, monkeypatch):
    """``figstyle.save`` returns the files that are there: none when a refused folder
    holds none (``pd-gains`` listed figures that did not exist), the earlier ones when
    it does (a complete read-only folder summarised again)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from kalman_vs_infoset.experiments import figstyle

    stem = tmp_path / "fig"
    written = figstyle.save(plt.figure(), stem)
    assert [p.name for p in written] == ["fig.png", "fig.svg"]
    _refuse_every_write(monkeypatch)
    with pytest.warns(RuntimeWarning, match="not written"):
        assert figstyle.save(plt.figure(), tmp_path / "new") == []
    with pytest.warns(RuntimeWarning, match="not written"):
        assert figstyle.save(plt.figure(), stem) == written
