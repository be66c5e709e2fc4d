"""Make results files again: each ``--json`` summary kept as a file names the command
that made it (``command``); this runs that command again, with ``--out`` in a scratch
folder, and compares the new summary with the file, number by number (not collected
by pytest: a tool, like ``fuzz_tightness.py``). Exit status 1 if a file's numbers
moved; files without a command (made before summaries named theirs) are listed, not
run.

    python tests/reproduce_results.py docs/results/tightness/corner/*.json

What a run cannot repeat is left out of the comparison: times (``wall_s``, ``cpu_s``,
``lp_s``), memory, the output folder and files, the machine and the code identity.
Numbers may differ by 1e-9 relative (linear algebra rounds differently on other CPUs).
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

#: keys whose values a run cannot repeat (anywhere in the summary)
UNREPEATABLE = frozenset(
    ("wall_s cpu_s lp_s worker_peak_rss_mb out files machine code command date").split()
)
REL_TOL = 1e-9


def differences(old, new, path: str = "") -> list[str]:
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


def rerun(command: str, scratch: Path) -> dict:
    """The summary of ``command`` run again, its ``--out`` in ``scratch`` (and from
    there, so that a command without ``--out`` writes there too)."""
    argv = shlex.split(command)
    if argv[:1] != ["kvi"]:
        raise ValueError(f"not a kvi command: {command!r}")
    argv = argv[1:]
    if "--out" in argv:
        argv[argv.index("--out") + 1] = str(scratch / "out")
    # the command line's own entry point, in this interpreter (a clone's .venv)
    entry = "import sys; from kalman_vs_infoset.experiments.cli import main; sys.exit(main())"
    cmd = [sys.executable, "-c", entry, *argv]
    done = subprocess.run(cmd, cwd=scratch, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        tail = done.stderr.strip().splitlines()[-1:] or [f"status {done.returncode}"]
        raise RuntimeError(tail[0])
    return json.loads(done.stdout.strip().splitlines()[-1])


def check(path: Path) -> tuple[str, list[str]]:
    """``(verdict, details)`` of one results file: ``same``, ``moved``, ``failed`` or
    ``no command``."""
    summary = json.loads(path.read_text(encoding="utf-8").strip().splitlines()[-1])
    command = summary.get("command") if isinstance(summary, dict) else None
    if not isinstance(command, str) or not command.startswith("kvi "):
        return "no command", []
    with tempfile.TemporaryDirectory() as scratch:
        try:
            new = rerun(command, Path(scratch))
        except (RuntimeError, ValueError, json.JSONDecodeError, IndexError) as exc:
            return "failed", [str(exc)]
    moved = differences(summary, new)
    return ("moved" if moved else "same"), moved


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("files", nargs="+", type=Path, help="results files (--json summaries)")
    args = p.parse_args(argv)
    bad = 0
    for path in args.files:
        verdict, details = check(path)
        print(f"{verdict:10s} {path}", flush=True)
        for line in details[:10]:
            print(f"    {line}")
        bad += verdict in ("moved", "failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
