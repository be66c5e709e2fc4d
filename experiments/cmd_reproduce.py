"""``kvi reproduce``: make kept ``--json`` summaries again and compare them with their
files, number by number.

Every command's ``--json`` summary names the command line that made it (``command``)
and the package's code (``code``: :func:`.provenance.code_identity`). :func:`check`
runs that command again in a separate process, from the current folder (a scenario
file may be named relative to it) with its output in a scratch folder, and lists what
moved. What a run cannot repeat is left out (:data:`UNREPEATABLE`:
times, memory, paths, the machine and the identities); numbers may differ by
:data:`REL_TOL` relative (linear algebra rounds differently on other CPUs).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import shlex
import subprocess
import sys
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from kalman_vs_infoset.experiments.errors import InputError

#: keys whose values a run cannot repeat, wherever they are in the summary
UNREPEATABLE = frozenset(
    "wall_s cpu_s lp_s worker_peak_rss_mb out files machine code command date".split()
)
#: commands whose summaries are measurements of time and memory: nothing to repeat
TIMINGS = frozenset({"bench"})
#: relative difference within which two numbers are the same
REL_TOL = 1e-9
#: the command line's own entry point, in this interpreter
_ENTRY = "import sys; from kalman_vs_infoset.experiments.cli import main; sys.exit(main())"


@dataclass(frozen=True)
class Verdict:
    """What :func:`check` found for one file: ``verdict`` is ``same``, ``moved``,
    ``failed`` (the command did not end in status 0), ``no command`` (a summary kept
    before summaries named theirs) or ``timings`` (a benchmark's, not run again: its
    numbers are the host's timings); ``details`` the moved values (and the fields
    today's code adds, which alone leave a file ``same``) or the error;
    ``same_code`` whether the file's code is today's (``None``: the file does not say)."""

    file: str
    verdict: str
    details: tuple[str, ...] = field(default_factory=tuple)
    same_code: bool | None = None


def differences(old: Any, new: Any, path: str = "") -> list[str]:
    """Where two summaries differ, as ``path: old -> new`` lines (empty: the same)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for key in sorted(set(old) | set(new)):
            if key in UNREPEATABLE:
                continue
            if key not in old or key not in new:
                out.append(f"{path}/{key}: {'missing now' if key in old else 'new'}")
                continue
            out += differences(old[key], new[key], f"{path}/{key}")
        return out
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{path}: {len(old)} items -> {len(new)}"]
        return [d for i, (a, b) in enumerate(zip(old, new, strict=True))
                for d in differences(a, b, f"{path}/{i}")]  # fmt: skip
    numbers = (int, float)
    if isinstance(old, numbers) and isinstance(new, numbers) and not isinstance(old, bool):
        if old == new or math.isclose(old, new, rel_tol=REL_TOL):
            return []
        if all(isinstance(v, float) and math.isnan(v) for v in (old, new)):
            return []
    elif old == new:
        return []
    return [f"{path}: {old!r} -> {new!r}"]


def read_summary(path: Path) -> dict[str, Any]:
    """The summary a results file keeps (its last line: a command's ``--json`` output);
    a file that is not one is bad input."""
    try:
        lines = Path(path).read_text(encoding="utf-8").strip().splitlines()
        summary = json.loads(lines[-1]) if lines else None
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"{path}: not a --json summary ({type(exc).__name__})") from None
    if not isinstance(summary, dict):
        raise InputError(f"{path}: not a --json summary (its last line is no JSON object)")
    return summary


def _scratch_argv(argv: list[str], scratch: Path) -> list[str]:
    """``argv`` with its output folder in ``scratch``: ``--out`` replaced, or added
    where the command takes one (without it, a command writes into the folder it runs
    from)."""
    out = str(scratch / "out")
    for i, arg in enumerate(argv):
        if arg == "--out" and i + 1 < len(argv):
            return [*argv[: i + 1], out, *argv[i + 2 :]]
        if arg.startswith("--out="):
            return [*argv[:i], f"--out={out}", *argv[i + 1 :]]
    from kalman_vs_infoset.experiments import cli

    try:  # (quietly: a command line its own parser refuses is the rerun's to say)
        with contextlib.redirect_stderr(io.StringIO()):
            args, _ = cli.build_parser(cli._command_named(argv)).parse_known_args(argv)
    except SystemExit:
        return argv
    return [*argv, "--out", out] if hasattr(args, "out") else argv


def rerun(argv: list[str], scratch: Path) -> dict[str, Any]:
    """The summary of ``kvi ARGV`` run again from the current folder (a scenario file
    may be named relative to it), its output in ``scratch``; ``RuntimeError`` with the
    command's last line on stderr if it did not end in status 0."""
    argv = _scratch_argv(argv, scratch)
    done = subprocess.run([sys.executable, "-c", _ENTRY, *argv], capture_output=True,
                          text=True, check=False)  # fmt: skip
    if done.returncode != 0:
        said = done.stderr.strip().splitlines()[-1:] or [""]
        raise RuntimeError(f"status {done.returncode}: {said[0]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def check(path: Path, summary: dict[str, Any], scratch: Path) -> Verdict:
    """Run the command of ``summary`` (kept in ``path``: :func:`read_summary`) again, its
    output in ``scratch``, and compare (:class:`Verdict`)."""
    from kalman_vs_infoset.experiments.provenance import code_identity

    command = summary.get("command")
    if not isinstance(command, str) or not command.startswith("kvi "):
        return Verdict(str(path), "no command")
    try:
        argv = shlex.split(command)[1:]
    except ValueError as exc:  # (an edited command with an unclosed quote)
        return Verdict(str(path), "failed", (f"command {command!r}: {exc}",))
    if argv[:1] and argv[0] in TIMINGS:  # (not run: its numbers are the host's timings)
        return Verdict(str(path), "timings")
    then = (summary.get("code") or {}).get("sources_sha256")
    same_code = None if then is None else then == code_identity()["sources_sha256"]
    try:
        new = rerun(argv, scratch)
    except (RuntimeError, ValueError, IndexError) as exc:
        return Verdict(str(path), "failed", (str(exc),), same_code)
    found = differences(summary, new)
    # a field today's code adds (the file was kept before it existed) moves no number
    moved = [d for d in found if not d.endswith(": new")]
    return Verdict(str(path), "moved" if moved else "same", tuple(found), same_code)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "files", nargs="+", type=Path, metavar="FILE",
        help="results files: a command's --json summary (its last line), which names "
        "the command that made it",
    )  # fmt: skip


def run(args: argparse.Namespace) -> dict[str, Any]:
    # every file read before the first command runs: a bad one stops nothing half-done
    summaries = [read_summary(path) for path in args.files]
    checked = []
    for path, summary in zip(args.files, summaries, strict=True):
        with tempfile.TemporaryDirectory(prefix="kvi-reproduce-") as scratch:
            checked.append(asdict(check(path, summary, Path(scratch))))
    return {"checked": checked}


def exit_status(result: dict[str, Any]) -> int:
    """1 when a file's numbers moved or its command failed, else 0."""
    return int(any(c["verdict"] in ("moved", "failed") for c in result["checked"]))


def render(result: dict[str, Any]) -> str:
    code = {True: "", False: " (written by other code)", None: ""}
    lines = []
    for c in result["checked"]:
        lines.append(f"{c['verdict']:<10}  {c['file']}{code[c['same_code']]}")
        lines += [f"    {d}" for d in c["details"][:10]]
        if len(c["details"]) > 10:
            lines.append(f"    ... {len(c['details']) - 10} more")
    return "\n".join(lines)
