"""Which code wrote a result: recorded beside every result file, checked on resume.

Resuming an interrupted experiment with different code would mix the runs of two
estimators (or two truth models) in one table without a trace. The runner records
:func:`code_identity` in each result's JSON and refuses to add runs to a file
written by other sources.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import inspect
import json
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from typing import Any, TypedDict

ROOT = Path(__file__).resolve().parents[1]
#: the packages whose sources decide a run's result
PACKAGES = ("estim", "guidance", "experiments")
#: presentation only (command line, tables, figures, summary statistics, file
#: writing): not hashed, so a new plot or a summary's fix does not refuse a resume
#: (none of them is imported by the code that computes a run's row)
PRESENTATION = (
    "cli.py",
    "__main__.py",
    "cmd_*.py",
    "plots.py",
    "plots_*.py",
    "figstyle.py",
    "report.py",
    "stats.py",
    "files.py",
    "paired.py",
)


class CodeIdentity(TypedDict):
    """What :func:`code_identity` returns (a plain dict at run time)."""

    version: str | None
    sources_sha256: str
    git_commit: str | None


@functools.cache
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


def _defining_modules(factory: Any) -> set[str]:
    """The modules whose code a factory runs: a ``functools.partial`` is its function's
    (and its callable arguments'), a bound method its function's, a callable instance
    its class's (a partial was identified as ``functools``: an edited plug-in resumed a
    table of its previous version)."""
    out: set[str] = set()
    todo, seen = [factory], set()
    while todo:
        f = todo.pop()
        if id(f) in seen:
            continue
        seen.add(id(f))
        if isinstance(f, functools.partial):
            todo += [f.func, *(a for a in (*f.args, *f.keywords.values()) if callable(a))]
        elif inspect.ismethod(f):
            todo += [f.__func__, type(f.__self__)]
        elif inspect.isfunction(f) or inspect.isclass(f):
            out.add(f.__module__)
        elif f is not None:  # a callable instance
            out.add(type(f).__module__)
    return out


def estimator_identity(problem: str, name: str) -> dict | None:
    """What identifies a plug-in estimator's code (``None`` for the package's own, which
    :func:`code_identity` covers): the modules of its factory and options outside the
    package, a SHA-256 over the sources of their top-level packages (by relative path
    and content; a script's own file when registered from one), and the versions of
    the distributions that install them. A resume compares it, so that a table never
    mixes the runs of two versions of a plug-in."""
    from kalman_vs_infoset.estim import registry

    try:
        reg = registry.get(problem, name)
    except KeyError:  # not a registered estimator: nothing beyond the package's code
        return None
    modules = {*_defining_modules(reg.factory), reg.options.__module__}
    outside = sorted(
        m
        for m in modules
        if m
        and not m.startswith("kalman_vs_infoset.")
        and m.split(".")[0] not in sys.stdlib_module_names
    )
    if not outside:
        return None
    files: dict[str, Path] = {}  # by path relative to its package's folder
    tops = sorted({m.split(".")[0] for m in outside})
    for top in tops:
        mod = sys.modules.get(top) or importlib.import_module(top)
        for folder in getattr(mod, "__path__", ()):  # a package: all its sources
            for f in Path(folder).rglob("*.py"):
                files[f"{top}/{f.relative_to(folder).as_posix()}"] = f
        source = getattr(mod, "__file__", None)
        if not hasattr(mod, "__path__") and source:
            files[Path(source).name] = Path(source)
    h = hashlib.sha256()
    for rel in sorted(files):
        h.update(rel.encode() + b"\0" + files[rel].read_bytes() + b"\0")
    known = metadata.packages_distributions()
    dists = sorted({d for top in tops for d in known.get(top, ())})
    return {
        "modules": outside,
        "sources_sha256": h.hexdigest() if files else None,
        "distributions": {d: metadata.version(d) for d in dists},
    }


def plug_ins(problem: str, names) -> list[str]:
    """The plug-in estimators (not the package's own) among ``names`` of ``problem``."""
    return [n for n in names if estimator_identity(problem, n) is not None]


def plugins_identity() -> dict[str, dict]:
    """:func:`estimator_identity` of every registered plug-in estimator, by
    ``problem/name`` (run on each Dask worker, so that a worker with another version of
    a plug-in is refused as one with other package sources is)."""
    from kalman_vs_infoset.estim import registry

    out = {}
    for problem in registry.PROBLEMS:
        for name in registry.names(problem):
            identity = estimator_identity(problem, name)
            if identity is not None:
                out[f"{problem}/{name}"] = identity
    return out


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
