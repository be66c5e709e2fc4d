"""Which code wrote a result: recorded beside every result file, checked on resume.

Resuming an interrupted experiment with different code would mix the runs of two
estimators (or two truth models) in one table without a trace. The runner records
:func:`code_identity` in each result's JSON and refuses to add runs to a file
written by other sources.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import TypedDict

ROOT = Path(__file__).resolve().parents[1]
#: the packages whose sources decide a run's result
PACKAGES = ("estim", "guidance", "experiments")
#: presentation only (command line, tables, figures, file writing): not hashed, so
#: a new plot does not refuse a resume
PRESENTATION = (
    "cli.py",
    "__main__.py",
    "cmd_*.py",
    "plots.py",
    "report.py",
    "files.py",
    "paired.py",
)


class CodeIdentity(TypedDict):
    """What :func:`code_identity` returns (a plain dict at run time)."""

    version: str | None
    sources_sha256: str
    git_commit: str | None


@cache
def code_identity() -> CodeIdentity:
    """Package version, SHA-256 over the sources of :data:`PACKAGES`, and the git
    commit of the package's own sources when known (:func:`_git_commit`; informational:
    the hash decides).

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
    """The commit of the package's own sources: the git checkout they are the top of
    (an editable install), else the commit pip recorded for an install from a git URL
    (``direct_url.json``); never that of a repository the package merely sits in (a
    virtual environment inside a user's project)."""
    try:
        top = subprocess.run(
            ["git", "rev-parse", "--show-toplevel", "HEAD"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=5,
        )
    except (OSError, subprocess.SubprocessError):
        top = None
    if top is not None and top.returncode == 0:
        lines = top.stdout.split()
        if len(lines) == 2 and Path(lines[0]).resolve() == ROOT:
            return lines[1]
    return _installed_commit()


def _installed_commit() -> str | None:
    try:
        text = metadata.distribution("kalman-vs-infoset").read_text("direct_url.json")
        commit = json.loads(text or "{}").get("vcs_info", {}).get("commit_id")
    except (metadata.PackageNotFoundError, ValueError, AttributeError):
        return None
    return str(commit) if commit else None


def sources_sha256() -> str:
    """This process's :func:`code_identity` hash (run on Dask workers to compare)."""
    return code_identity()["sources_sha256"]
