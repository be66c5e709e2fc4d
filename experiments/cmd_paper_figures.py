"""``kvi paper-figures [--out results/figures] [--runs N]``.

Redraws every figure of the papers that our models cover, each file named after the
paper's figure (PNG and SVG): seed 003 ``kp_fig3``, ``kp_fig4``, ``kp_fig5`` (and our
``kp_fig3_overlay``: the set, EKF and UKF on one realisation), seed 000
``resurs_fig1``-``resurs_fig9`` with ``resurs_inertia_signs`` (the index under the
readings of the lost signs of the products of inertia) and ``resurs_noisy`` (the turn
under noisy measurements through an estimator), seed 001 ``akimov_fig3``-``fig15``,
seed 002 ``lqr_lyapunov`` (its Lyapunov function along the LQR turn), and the gyrostat
turn of seed 004 (``gyrostat_eta``, ``gyrostat_switching``, ``gyrostat_torques``; its
paper has no figures we can read). The
paper's printed numbers are marked on them (black stars and dotted lines, "paper: ...").
``--runs`` is the number of engagements per curve of ``kp_fig5`` (the paper: 50); the
runs are kept in ``<out>/runs`` and reused (resumed) by the next call. ``--quick``
coarsens the gain study (grid 0.1 instead of 0.025, four angles for ``f0``) and the
attitude loops' steps (Resurs-P 0.5 s, the wheels 20 Hz, the gyrostat 5 Hz) for previews
and tests; the figure titles say so, and their numbers are not the paper runs' (the
energy law's turn of Resurs-P does not complete at 0.5 s: 27.7 deg left at 300 s).
Writes ``paper_figures.json`` with the numbers each figure shows (ours and the
paper's), from which ``docs/figures.md`` is written.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.files import atomic_write
from kalman_vs_infoset.experiments.options import non_empty, out_folder, positive_int

#: the figures run engagements (the command line announces a compilation of the kernels)
COMPILED_KERNELS = True


@cache
def _tables() -> tuple[dict[str, str], dict[str, Callable[..., dict[str, Any]]]]:
    """:data:`FIGURES` and :data:`GROUPS`, from the modules that draw the figures: they
    import matplotlib and the simulations, so they are imported on first use (drawing, or
    these names), not to declare the command's arguments."""
    from kalman_vs_infoset.experiments import paper_figs_attitude as att
    from kalman_vs_infoset.experiments import paper_figs_kp as kp
    from kalman_vs_infoset.experiments import paper_figs_more as more
    from kalman_vs_infoset.experiments import paper_figs_resurs as resurs
    from kalman_vs_infoset.experiments import paper_figs_resurs_more as resurs_more

    figures: dict[str, str] = {
        **{name: fn.__name__.replace("fig", "kp_fig") for name, fn in kp.FIGURES.items()},
        **resurs.FIGURES,
        **resurs_more.FIGURES,
        **att.FIGURES,
        **more.FIGURES,
    }
    groups = {
        "kp_fig3": kp.fig3,
        "kp_fig4": kp.fig4,
        "kp_fig5": kp.fig5,
        **resurs.GROUPS,
        **resurs_more.GROUPS,
        **att.GROUPS,
        **more.GROUPS,
    }
    return figures, groups


def __getattr__(name: str) -> Any:
    """``FIGURES`` (figure name -> the group that draws it; a group draws all its figures
    at once) and ``GROUPS`` (group -> its drawing function), built on first use."""
    if name == "FIGURES":
        return _tables()[0]
    if name == "GROUPS":
        return _tables()[1]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: names of --only that stand for several groups
ALIASES = {
    "kp": ["kp_fig3", "kp_fig4", "kp_fig5"],
    "resurs": ["resurs", "resurs_more"],
    "akimov": ["akimov", "akimov_more"],
}


@dataclass
class Context:
    """Where and how the figures are drawn."""

    out: Path
    runs: int
    quick: bool
    scenarios: Path
    written: list[Path] = field(default_factory=list)

    def save(self, fig, name: str) -> None:
        from kalman_vs_infoset.experiments import figstyle as fs

        if self.quick and fig._suptitle is not None:
            fig._suptitle.set_text(fig._suptitle.get_text() + " [--quick]")
        self.written += fs.save(fig, self.out / name)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="results/figures", help="folder (default results/figures)")
    p.add_argument(
        "--runs",
        type=positive_int,
        default=50,
        help="engagements per kp_fig5 curve (default 50, the paper's)",
    )
    p.add_argument(
        "--only",
        default=None,
        help="comma-separated figure names or groups (kp, resurs, akimov, gyrostat, lqr); "
        "a figure's name draws every figure of its group (they share its runs)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="coarser gain study and attitude steps, for previews and tests: the figures "
        "are drawn, their numbers are not the paper runs' (Resurs-P's turn does not "
        "complete at the coarse 0.5-s step)",
    )
    p.add_argument("--scenarios", type=non_empty,
                   help="folder of the scenario files (default: the bundled ones)")  # fmt: skip


def _groups(only: str | None) -> list[str]:
    figures, drawers = _tables()
    if only is None:
        return list(drawers)
    parts = [w.strip() for w in only.split(",")]
    wanted = [w for w in parts if w]
    if not wanted:  # would draw nothing and say so with exit status 0
        raise InputError(f"--only {only!r}: name at least one figure or group")
    # as the other lists: an empty name or one given twice is a typo, not a request
    twice = sorted({w for w in wanted if wanted.count(w) > 1})
    if len(wanted) < len(parts) or twice:
        what = f"{', '.join(twice)} given twice" if twice else "an empty name"
        raise InputError(f"--only {only!r}: {what}")
    groups = []
    for w in wanted:
        if w in figures:
            g = figures[w]
        elif w in ALIASES:
            groups += ALIASES[w]
            continue
        elif w in drawers:
            g = w
        else:
            raise InputError(
                f"--only: unknown figure or group '{w}' "
                f"(figures: {', '.join(figures)}; groups: kp, resurs, akimov, lqr, "
                "gyrostat)"
            )
        groups.append(g)
    return list(dict.fromkeys(groups))


def run(args) -> dict[str, Any]:
    from kalman_vs_infoset.experiments.scenario import scenario_folder

    drawers = _tables()[1]
    scenarios = scenario_folder(args.scenarios)
    # refused before any figure is drawn, as every command does
    out = out_folder(args.out, Path("results") / "figures")
    ctx = Context(out, args.runs, args.quick, scenarios)
    numbers: dict[str, Any] = {}
    t0 = time.perf_counter()
    for group in _groups(args.only):
        t1 = time.perf_counter()
        numbers.update(drawers[group](ctx))
        print(f"paper-figures: {group} in {time.perf_counter() - t1:.1f} s", file=sys.stderr)
    path = ctx.out / "paper_figures.json"
    try:  # figures drawn by an earlier call (--only) keep their numbers
        before = json.loads(path.read_text())
        if before.get("runs") == args.runs and before.get("quick") == args.quick:
            numbers = {**before.get("numbers", {}), **numbers}
    except (OSError, ValueError, AttributeError):
        pass
    meta = {"runs": args.runs, "quick": args.quick, "numbers": numbers}
    atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(meta, indent=2, default=str)))
    return {
        "out": str(ctx.out),
        "figures": sorted({p.stem for p in ctx.written}),
        "files": [str(p) for p in ctx.written] + [str(path)],
        "numbers": numbers,
        "wall_s": time.perf_counter() - t0,
    }


def render(result: dict[str, Any]) -> str:
    lines = [f"{len(result['figures'])} figures in {result['out']} ({result['wall_s']:.0f} s):"]
    lines += ["  " + ", ".join(result["figures"])]
    return "\n".join(lines)
