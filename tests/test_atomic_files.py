"""Atomic writes when a process is killed between writing and renaming (``kill -9``,
an out-of-memory kill): the temporary file is hidden, so that reading the folder as
one Parquet dataset does not read a second copy of its runs, and the next write of the
same file removes it once its process is gone."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from kalman_vs_infoset.experiments.files import atomic_write


def _dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def _table(path, runs) -> None:
    atomic_write(path, lambda tmp: pd.DataFrame({"run": runs}).to_parquet(tmp))


def test_a_killed_writers_temporary_table_is_not_read_and_is_removed_later(tmp_path):
    path = tmp_path / "sc-infoset-random-s1.parquet"
    _table(path, [0, 1, 2])
    # what a writer killed between its write and its rename leaves (a complete table)
    stale = tmp_path / f".{path.name}.{_dead_pid()}.abc123.tmp"
    pd.DataFrame({"run": [0, 1, 2]}).to_parquet(stale)
    live = tmp_path / f".{path.name}.{__import__('os').getpid()}.def456.tmp"  # mid-write
    live.write_bytes(b"")
    assert sorted(pd.read_parquet(tmp_path)["run"]) == [0, 1, 2]  # hidden: not read
    _table(path, [0, 1, 2, 3])
    assert not stale.exists() and live.exists()  # only a dead process's is removed
    assert sorted(pd.read_parquet(tmp_path)["run"]) == [0, 1, 2, 3]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([path.name, live.name])


def test_a_failed_write_leaves_no_temporary_file(tmp_path):
    path = tmp_path / "table.parquet"

    def fails(tmp):
        open(tmp, "w").write("half")
        raise OSError("disk full")

    try:
        atomic_write(path, fails)
    except OSError:
        pass
    assert list(tmp_path.iterdir()) == []


def test_the_bytes_reach_the_disk_before_the_name_points_at_them(tmp_path, monkeypatch):
    """A power loss after the rename must find the new bytes, not an empty file: the
    temporary file is synced before ``os.replace``, the folder (the rename) after it."""
    import os

    from kalman_vs_infoset.experiments import files

    if not Path("/proc/self/fd").is_dir():
        pytest.skip("names the synced files through /proc (Linux)")
    events: list[tuple[str, str]] = []
    fsync, replace = os.fsync, os.replace

    def synced(fd: int) -> None:
        events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}")))
        fsync(fd)

    def renamed(src, dst) -> None:
        events.append(("replace", str(dst)))
        replace(src, dst)

    monkeypatch.setattr(os, "fsync", synced)
    monkeypatch.setattr(os, "replace", renamed)
    target = tmp_path / "table.parquet"
    files.atomic_write(target, lambda tmp: Path(tmp).write_bytes(b"rows"))
    assert [kind for kind, _ in events] == ["fsync", "replace", "fsync"]
    assert events[0][1].startswith(str(tmp_path / ".table.parquet."))  # the temporary file
    assert events[2][1] == str(tmp_path)  # the folder
    assert target.read_bytes() == b"rows"
