"""The command line's shared options: one spelling and one parser for each.

Every command takes its options from here, so a flag means the same everywhere:

* ``--estimators NAME[,NAME...]``: a comma list of registered estimators, checked against
  the registry (:mod:`kalman_vs_infoset.estim.registry`) while the command line is parsed,
  before any work; empty lists and names given twice are refused. The old singular
  ``--estimator`` is refused in one line naming the new flag (argparse would otherwise
  take it as an abbreviation of ``--estimators``).
* ``--noise NAME[,NAME...]``: a comma list from the command's noise vocabulary.
* ``--runs``, ``--seed``, ``--workers``, ``--run-cpu-limit-s``,
  ``--run-memory-limit-mb``: bounded numbers.
* ``--trace RUNS``: the runs whose per-step history is recorded (:mod:`.traces`).
* :func:`add_common` and :func:`resolve`: a scenario's Monte Carlo options.

Bad input is an ``argparse`` error: one line on stderr and exit status 2.

This module stays light: declaring a command's arguments imports no numerical library
beyond numpy (the registry's options models), so that ``kvi CMD --help`` starts fast;
the runner, the simulations and the plots are imported by the commands' ``run``.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from kalman_vs_infoset.experiments.errors import InputError

#: largest root seed (Parquet's int64 column; --seed is validated before any run); the
#: runner checks it too (here, so that parsing does not import the runner)
MAX_SEED = 2**63 - 1

#: most runs a command may ask for (the runner holds their indices in memory)
MAX_RUNS = 10**6

#: most runs one --trace may name (each is replayed with every step recorded)
MAX_TRACED = 20

#: the help of a command's scenario argument
SCENARIO_HELP = "a bundled scenario's name (`kvi scenarios` lists them) or a scenario TOML file"


def _int_where(lo: int, hi: float, expected: str) -> Callable[[str], int]:
    """An argparse ``type``: an integer in ``[lo, hi]``, else "expected ``expected``"."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = lo - 1
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value

    return parse


def _int_at_least(lo: int, what: str) -> Callable[[str], int]:
    return _int_where(lo, float("inf"), f"a {what} integer")


positive_int = _int_at_least(1, "positive")


def non_empty(text: str) -> str:
    """An argparse ``type``: a text that is not blank (an empty ``--scheduler`` ran
    locally, an empty ``--scenarios`` read the bundled scenarios, both without a word)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a value, got an empty text")
    return text


def int_in(lo: int, hi: int) -> Callable[[str], int]:
    """An argparse ``type``: an integer in ``[lo, hi]``."""
    return _int_where(lo, hi, f"an integer in [{lo}, {hi}]")


def runs_int(text: str) -> int:
    """A run count: an integer in [1, 10^6] (the runner holds the run indices)."""
    value = positive_int(text)
    if value > MAX_RUNS:
        raise argparse.ArgumentTypeError(f"expected an integer in [1, {MAX_RUNS}], got {text!r}")
    return value


def seed_int(text: str) -> int:
    """A root seed: an integer in [0, 2^63 - 1] (the results tables hold it as int64)."""
    value = _int_at_least(0, "non-negative")(text)
    if value > MAX_SEED:
        raise argparse.ArgumentTypeError(f"expected an integer in [0, 2^63 - 1], got {text!r}")
    return value


def cpu_limit_s(text: str) -> float:
    """A CPU-time limit of a run, in seconds: a number in (0, 1e6]."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 < value <= 1e6:
        raise argparse.ArgumentTypeError(f"expected seconds in (0, 1e6], got {text!r}")
    return value


def memory_limit_mb(text: str) -> float:
    """A memory limit of a run, in MiB: a number in [1, 1e7], on Linux only."""
    from kalman_vs_infoset.experiments.limits import MEMORY_LIMIT_SUPPORTED

    if not MEMORY_LIMIT_SUPPORTED:
        raise argparse.ArgumentTypeError("a run's memory can be limited on Linux only")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 1.0 <= value <= 1e7:
        raise argparse.ArgumentTypeError(f"expected MiB in [1, 1e7], got {text!r}")
    return value


def split_list(text: str, allowed: Sequence[str], what: str) -> list[str]:
    """A comma list of names from ``allowed``: none missing, unknown or given twice
    (``ValueError`` of one line otherwise)."""
    parts = [t.strip() for t in str(text).split(",")]
    items = [t for t in parts if t]
    bad = [t for t in items if t not in allowed]
    if not items or bad or len(items) < len(parts):
        got = f"unknown {', '.join(bad)}" if bad else "an empty name" if items else "an empty list"
        raise ValueError(
            f"expected a comma-separated list of {what} from {', '.join(allowed)}; "
            f"got {got} in {text!r}"
        )
    twice = sorted({t for t in items if items.count(t) > 1})
    if twice:  # each would be run and tabled twice
        raise ValueError(f"{', '.join(twice)} given twice in {text!r}")
    return items


#: the largest time a --times list takes (s): far beyond any scenario's horizon, and far
#: from where a time over the step overflows
MAX_TIME_S = 1e6


def times_s(positive: bool) -> Callable[[str], list[float]]:
    """An argparse ``type``: a comma list of times in s, sorted: each a number in ``[0,
    MAX_TIME_S]`` (``(0, ...]`` if ``positive``), none empty or given twice."""
    least = "positive" if positive else "non-negative"

    def parse(text: str) -> list[float]:
        parts = [t.strip() for t in str(text).split(",")]
        try:
            values = [float(t) for t in parts]
        except ValueError:
            values = []
        ok = [v == v and (v > 0 if positive else v >= 0) and v <= MAX_TIME_S for v in values]
        if not values or not all(ok):
            raise argparse.ArgumentTypeError(
                f"expected comma-separated {least} times in s, at most "
                f"{MAX_TIME_S:.0f}; got {text!r}"
            )
        twice = sorted({v for v in values if values.count(v) > 1})
        if twice:
            raise argparse.ArgumentTypeError(f"{twice[0]:g} s given twice in {text!r}")
        return sorted(values)

    return parse


def list_of(allowed: Sequence[str], what: str = "names") -> Callable[[str], list[str]]:
    """An argparse ``type``: :func:`split_list` with its error as an argparse error."""
    allowed = tuple(allowed)

    def parse(text: str) -> list[str]:
        try:
            return split_list(text, allowed, what)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse


class _Renamed(argparse.Action):
    """An old flag: refused in one line naming the one that replaced it."""

    def __init__(self, option_strings, dest, new: str = "", **kwargs) -> None:
        self.new = new
        super().__init__(option_strings, dest, nargs="?", help=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        example = f"{self.new} {values}" if values else self.new
        parser.error(f"{option_string} is now {self.new} (a comma list), e.g. {example}")


def add_estimators(
    p: argparse.ArgumentParser,
    problem: str,
    default: list[str] | None,
    help_default: str,
    most: int | None = None,
) -> None:
    """``--estimators`` of ``problem`` (``"intercept"`` or ``"attitude"``), and the
    refusal of ``--estimator``. ``most`` caps the list's length (a command that studies
    one estimator at a time)."""
    from kalman_vs_infoset.estim import registry  # the registry, not the parser, is heavy

    names = registry.names(problem)
    parse = list_of(names, f"{problem} estimators")
    if most is not None:
        many = parse

        def parse(text: str) -> list[str]:
            items = many(text)
            if len(items) > most:
                raise argparse.ArgumentTypeError(
                    f"this command takes at most {most} estimator(s), got {text!r}"
                )
            return items

    p.add_argument(
        "--estimators",
        type=parse,
        default=default,
        metavar="NAME[,NAME...]",
        help=f"comma-separated, from {','.join(names)} (default: {help_default})",
    )
    p.add_argument("--estimator", action=_Renamed, new="--estimators")


def add_noise(
    p: argparse.ArgumentParser, allowed: Sequence[str], default: list[str] | None, help_default: str
) -> None:
    """``--noise``: a comma list from ``allowed`` (the command's noise vocabulary)."""
    p.add_argument(
        "--noise",
        type=list_of(allowed, "noises"),
        default=default,
        metavar="NAME[,NAME...]",
        help=f"comma-separated, from {','.join(allowed)} (default: {help_default})",
    )


def parse_runs(text: str) -> list[int]:
    """``--trace 0,3`` -> ``[0, 3]`` (non-negative run ids, no repeats); ``none`` ->
    ``[]`` (no run, where a command traces one by default)."""
    if str(text).strip().lower() == "none":
        return []
    items = [t.strip() for t in str(text).split(",")]
    try:
        runs = [int(t) for t in items]  # an empty item ("0,,3") is not a run id
    except ValueError:
        runs = []
    if not runs or min(runs) < 0 or len(set(runs)) != len(runs) or len(runs) > MAX_TRACED:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of distinct run ids >= 0 (at most {MAX_TRACED}), "
            f"e.g. 0,3, or 'none'; got {text!r}"
        )
    return runs


def add_trace(p: argparse.ArgumentParser, default: str = "") -> None:
    """``--trace RUNS``: record these runs' per-step history (:mod:`.traces`);
    ``default``: what the command traces without the option, if anything."""
    p.add_argument(
        "--trace",
        type=parse_runs,
        default=None,
        metavar="RUNS",
        help=f"record the per-step history of these runs (e.g. 0,3; at most {MAX_TRACED}; 'none': "
        "no run) as "
        "<results>-trace.parquet in the _traces folder beside the run tables, and draw "
        "their figures" + (f" (default: {default})" if default else ""),
    )


def add_limit(p: argparse.ArgumentParser) -> None:
    """``--run-cpu-limit-s`` and ``--run-memory-limit-mb`` (:func:`run_limits`)."""
    p.add_argument(
        "--run-cpu-limit-s",
        type=cpu_limit_s,
        help="CPU-time limit of one run, s (a run over it is recorded as failed, with the "
        "reason; local runs only; default: none)",
    )
    p.add_argument(
        "--run-memory-limit-mb",
        type=memory_limit_mb,
        help="memory one run may add to its process, MiB (a run over it is recorded as "
        "failed, with the reason, instead of the system ending the worker; local runs, "
        "Linux only; default: none)",
    )


def run_limits(args: argparse.Namespace):
    """The :class:`~experiments.limits.RunLimits` of :func:`add_limit`'s options."""
    from kalman_vs_infoset.experiments.limits import RunLimits

    return RunLimits(args.run_cpu_limit_s, args.run_memory_limit_mb)


def add_runner(p: argparse.ArgumentParser) -> None:
    """Where the runs go: ``--workers``, ``--scheduler``, ``--no-progress``, the limit and
    ``--rerun-other-code``."""
    p.add_argument(
        "--workers", type=positive_int,
        help="local worker processes (default: the CPUs this process may run on)",
    )  # fmt: skip
    p.add_argument("--scheduler", type=non_empty, help="Dask scheduler address (tcp://host:8786)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_limit(p)
    p.add_argument(
        "--rerun-other-code",
        action="store_true",
        help="run again the runs of a results table in --out that other code wrote (an "
        "earlier version of the package), replacing it; default: refuse such a table "
        "(finished runs of this code are always resumed)",
    )


def add_overrides(p: argparse.ArgumentParser, example: str) -> None:
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        dest="overrides",
        help=f"override a scenario field with a TOML value, e.g. {example} (repeatable; "
        "validated like the file; the scenario's name gets a +key=value suffix)",
    )


def add_common(p: argparse.ArgumentParser) -> None:
    """A scenario's Monte Carlo options (the intercept commands)."""
    p.add_argument("scenario", help=SCENARIO_HELP)
    p.add_argument("--runs", type=runs_int, help="number of runs (default: the scenario's)")
    p.add_argument("--seed", type=seed_int, help="root seed (default: the scenario's)")
    p.add_argument("--out", help="output directory (default: results/<scenario name>)")
    add_runner(p)
    add_overrides(p, "estimator.ekf.noise_inflation=10")


#: the noises of ``compare`` and ``sweep`` when ``--noise`` is not given
GRID_NOISES = ("random", "game")


def add_grid(p: argparse.ArgumentParser, trace: bool = True) -> None:
    """A scenario's options, ``--trace`` (with ``trace``), ``--estimators`` (default: all)
    and ``--noise`` (default: random,game): the estimators x noises of ``compare`` and
    ``sweep``."""
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.experiments.noise import NOISES

    add_common(p)
    if trace:
        add_trace(p)
    add_estimators(p, "intercept", list(registry.names("intercept")), "all")
    add_noise(p, NOISES, list(GRID_NOISES), ",".join(GRID_NOISES))


def out_folder(given: str | None, default: Path) -> Path:
    """``--out`` or ``default``; refused in one line when it names a file."""
    out = Path(given) if given else default
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: not a directory")
    return out


def writable_folder(folder: Path, flag: str = "--out") -> Path:
    """``folder``, made if missing; refused in one line when the system does not let this
    process write a file there (read-only, no permission, immutable): for a command
    whose output is only files, which would otherwise be skipped one warning each."""
    import os
    import tempfile

    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".kvi-probe.", suffix=".tmp", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"{flag} {folder}: cannot write there ({exc.strerror})") from None
    return folder


def resolve(args: argparse.Namespace) -> tuple[Any, int, int, Path]:
    """The intercept scenario of :func:`add_common`'s options with its runs, seed and
    output folder (the scenario's where an option is not given)."""
    from kalman_vs_infoset.experiments.scenario import load_scenario

    sc = load_scenario(args.scenario, args.overrides)
    runs = args.runs or sc.experiment.runs
    seed = sc.experiment.seed if args.seed is None else args.seed
    return sc, runs, seed, out_folder(args.out, Path("results") / sc.name)
