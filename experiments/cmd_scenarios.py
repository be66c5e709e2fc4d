"""``kvi scenarios``: the bundled scenarios, one line each.

Each line gives the scenario's name (what ``kvi intercept NAME`` or ``kvi attitude NAME``
accepts in place of a file), the command that runs it and its ``description``; ``--path``
adds the file's location (a starting point for a scenario of one's own).
"""

from __future__ import annotations

import argparse
from typing import Any

from kalman_vs_infoset import data as bundled


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--path", action="store_true", help="also print each file's location")


def run(args: argparse.Namespace) -> dict[str, Any]:
    rows = [bundled.scenario_summary(n) for n in bundled.scenario_names()]
    if args.path:
        for row in rows:
            row["path"] = str(bundled.scenario_file(row["name"]))
    return {"scenarios": rows}


def render(result: dict[str, Any]) -> str:
    rows = result["scenarios"]
    width = max(len(r["name"]) for r in rows)
    lines = []
    for r in rows:
        line = f"{r['name']:<{width}}  {r['command']:<9}  {r['description']}"
        lines.append(line + (f"\n{'':<{width}}  {r['path']}" if "path" in r else ""))
    return "\n".join(lines)
