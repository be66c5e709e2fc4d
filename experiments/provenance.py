"""Which code wrote a result: recorded beside every result file, checked on resume.

Resuming an interrupted experiment with different code would mix the runs of two
estimators (or two truth models) in one table without a trace. The runner records
:func:`code_identity` in each result's JSON and refuses to add runs to a file
written by other sources.
"""

from __future__ import annotations

import hashlib
import subprocess
from functools import cache
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the packages whose sources decide a run's result
PACKAGES = ("estim", "guidance", "experiments")
#: presentation only (command line, tables, figures, file writing): not hashed, so
#: a new plot does not refuse a resume
PRESENTATION = ("cli.py", "__main__.py", "cmd_*.py", "plots.py", "report.py", "files.py")


@cache
def code_identity() -> dict[str, str | None]:
    """Package version, SHA-256 over the sources of :data:`PACKAGES`, and the git
    commit when the sources are a git checkout (informational: the hash decides).

    The hash covers every ``*.py`` file but the :data:`PRESENTATION` modules, by
    relative path and content, so it changes with uncommitted edits too, and needs
    no git.
    """
    h = hashlib.sha256()
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*.py")):
            if any(f.match(pattern) for pattern in PRESENTATION):
                continue
            h.update(f.relative_to(ROOT).as_posix().encode() + b"\0")
            h.update(f.read_bytes() + b"\0")
    try:
        version = metadata.version("kalman-vs-infoset")
    except metadata.PackageNotFoundError:
        version = None
    return {"version": version, "sources_sha256": h.hexdigest(), "git_commit": _git_commit()}


def _git_commit() -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, timeout=5
        )
    except (OSError, subprocess.SubprocessError):
        return None
    if out.returncode != 0:
        return None
    return out.stdout.strip() or None


def sources_sha256() -> str:
    """This process's :func:`code_identity` hash (run on Dask workers to compare)."""
    return str(code_identity()["sources_sha256"])
