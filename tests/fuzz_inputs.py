"""Random command lines: every one must end in exit status 0, or 2 with one line on
stderr, never a traceback (not collected by pytest: a tool, like ``fuzz_scenarios.py``).

Three kinds of case, drawn in turn:

- ``set``: ``kvi intercept`` on a short scenario with one to three ``--set`` overrides of
  any field of the intercept scenario or of an estimator's options table;
- ``attitude``: ``kvi attitude`` on a short turn or a bundled scenario, overriding any
  field of its simulation's tables or of an attitude estimator's options;
- ``flags``: a command's own options (``--runs``, ``--times``, ``--values``, ...) given
  edge values (0, -1, nan, inf, empty, lists, words).

A value is near the field's default half the time (scaled, negated, its interval
reversed, one end moved), else from a list of edge values of every type, so that some
commands run and most are refused. Each command runs in this process with a CPU-time
limit; a command over it is counted, not failed, as are runs reported failed (exit
status 1, e.g. over ``--run-cpu-limit-s``). This search found
``estimator.options=7`` raising an ``AttributeError``, and every Resurs-P run failing
with a rotor momentum of 1e-300 N m s (``ZeroDivisionError`` in the gyrodines'
steering). Exit status 1 if a command raised, a run failed otherwise than by its limits,
or a refusal took more than one line.

    python tests/fuzz_inputs.py --cases 300 --seed 1
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import random
import re
import sys
import tempfile
import traceback
import typing
import zlib
from collections import Counter
from pathlib import Path

import pydantic_core

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness_texts import SHORT, TINY_RW  # noqa: E402
from time_limit import TimeLimit  # noqa: E402

EDGE_VALUES = (
    "0", "-1", "1", "1e-300", "1e300", "nan", "inf", "-inf", "0.5", "2", "100", '"x"', "true",
    "[]", "[1.0]", "[1.0, 2.0]", "[2.0, 1.0]", "[0.0, 0.0]", "[-1e9, 1e9]", "[nan, 1.0]",
    "[1.0, 2.0, 3.0]", "1e-9", "-0.0", "12345678901234567890", '"auto"', '"nodes"', "{}",
    "[1, 2]", "[0.0, 0.0, 1.0]", "[1.0, 0.0, 0.0, 0.0]", '"pd"', '"game"',
)  # fmt: skip
EDGE_FLAGS = (
    "0", "-1", "1", "nan", "inf", "-inf", "1e9", "abc", "", "0.5", "2", ",", "1,2", "-0",
    "1e-9", "3", "100", "5,4", "0,0", "1,,2", "random", "game", "x,y", " ", "1e308", "0x10",
)  # fmt: skip
COMMON = ("--runs", "--seed", "--workers", "--run-cpu-limit-s", "--run-memory-limit-mb")
#: command -> (its arguments, the options a case varies)
COMMANDS = {
    "intercept": (["{short}"], (*COMMON, "--trace", "--estimators", "--noise")),
    "compare": (["{short}"], (*COMMON, "--trace", "--estimators", "--noise")),
    "adversaries": (["{short}"], (*COMMON, "--estimators", "--lookahead")),
    "sweep": (["{short}", "--key", "model.nu_mps2", "--values", "[0.005, 0.01]"],
              (*COMMON, "--estimators", "--noise", "--key", "--values")),
    "tightness": (["{short}"], ("--noise", "--seed", "--times", "--estimators", "--switch-s")),
    "attitude": (["{tiny}"], (*COMMON, "--trace", "--controller", "--noise", "--estimators")),
    "attitude-tightness": (["{tiny}", "--times", "0.1"],
                           ("--noise", "--seed", "--times", "--estimators", "--controller")),
    "pd-gains": (["--no-figures"], (
        "--angles-deg", "--quaternion-term", "--initial-turn", "--angle-tol-deg",
        "--rate-tol-degps", "--grid-step", "--control-period-s", "--horizon-s",
        "--fit-loss", "--map-angle-deg", "--fig15-kw")),
    "fig5": ([], ("--runs", "--seed", "--estimators", "--scenarios", "--workers")),
    "paper-figures": (["--quick"], ("--runs", "--only", "--scenarios")),
}  # fmt: skip
#: more values for some options
FLAG_VALUES = {
    "--values": ("[]", "[1]", "[nan]", "[1, 1]", "[0.005, -1]", "x", "[[1]]", '["a"]'),
    "--key": ("model.nope", "estimator.infoset.n_nodes", "name", "", "model"),
}
#: the errors of a run stopped by its limits (a run that raised anything else is a fault)
LIMITS = {"RunTimeout", "MemoryError"}
#: the errors of a run that cannot go on, said as such: the end-to-end intercept's axis
#: loop diverged, or an attitude UKF's covariance lost definiteness
REPORTED = ("LoopDiverged: ", "LinAlgError: the UKF diverged")
RUNS_ONE = ("intercept", "compare", "adversaries", "sweep", "fig5", "attitude")


def leaves(model, prefix: str = "") -> list[tuple[str, typing.Any]]:
    """``(TABLE.KEY, default)`` of every field of a pydantic model, nested tables
    flattened."""
    import pydantic

    out = []
    for name, info in model.model_fields.items():
        kinds = (info.annotation, *typing.get_args(info.annotation))
        tables = [k for k in kinds if isinstance(k, type) and issubclass(k, pydantic.BaseModel)]
        if tables:
            out += leaves(tables[0], f"{prefix}{name}.")
        else:
            out.append((prefix + name, info.default))
    return out


def field_keys(kind: str) -> dict[str, list[tuple[str, typing.Any]]]:
    """The fields of each scenario of ``kind`` (a bundled name or ``{tiny}``/``{short}``),
    with every estimator's options table."""
    from kalman_vs_infoset.estim import registry

    def options(problem: str, prefix: str) -> list[tuple[str, typing.Any]]:
        fields = {name: registry.get(problem, name).options.model_fields
                  for name in registry.names(problem)}  # fmt: skip
        return [(f"{prefix}.{name}.{key}", info.default)
                for name, table in fields.items() for key, info in table.items()]  # fmt: skip

    if kind == "set":
        from kalman_vs_infoset.experiments.sim.intercept_config import InterceptScenario

        own = [(k, d) for k, d in leaves(InterceptScenario) if k != "estimator.options"]
        return {"{short}": own + [("estimator.options", {})] + options("intercept", "estimator")}
    from kalman_vs_infoset.experiments.scenario import read
    from kalman_vs_infoset.experiments.sim.attitude_cmg_config import CmgScenario
    from kalman_vs_infoset.experiments.sim.attitude_rw_config import RwScenario
    from kalman_vs_infoset.experiments.sim.gyrostat_config import GyrostatScenario

    est = options("attitude", "estimator_options")
    models = {"{tiny}": RwScenario, "smallsat_rw": RwScenario, "lqr_large_angle": RwScenario,
              "resurs_p": CmgScenario, "gyrostat_game": GyrostatScenario}  # fmt: skip

    def written(scenario: str, key: str, default):
        """A field without a default (the inertia, say) is drawn near the bundled file's
        value (``{tiny}`` is smallsat_rw shortened)."""
        if default is not pydantic_core.PydanticUndefined:
            return default
        table: typing.Any = read("smallsat_rw" if scenario == "{tiny}" else scenario)[0]
        for part in key.split("."):
            table = table.get(part) if isinstance(table, dict) else None
        return table

    return {scenario: [(k, written(scenario, k, d)) for k, d in leaves(model)] + est
            for scenario, model in models.items()}  # fmt: skip


def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def near_default(default, rng: random.Random) -> str | None:
    """A value near a numeric (or boolean) default, or ``None`` for other fields."""
    f = rng.choice((0.0, 0.1, 0.5, 0.9, 1.1, 2.0, 10.0, 1e3, -1.0, 1e-6))
    if isinstance(default, bool):
        return _toml(not default)
    if isinstance(default, int | float):
        value = default * f if default else rng.choice((1e-6, 0.1, 1.0, 10.0, -1.0))
        return _toml(int(value) if isinstance(default, int) else float(value))
    if (
        isinstance(default, list | tuple)
        and default
        and all(isinstance(v, int | float) for v in default)
    ):
        values = [float(v) for v in default]
        how = rng.randrange(4)
        if how == 0:
            values = [v * f for v in values]
        elif how == 1:
            values.reverse()
        elif how == 2:
            values = [v * rng.choice((0.9, 1.0, 1.1, 1.5)) for v in values]
        else:
            values[rng.randrange(len(values))] *= f
        return _toml(values)
    return None


def draw(kind: str, rng: random.Random, keys, files: dict[str, Path], out: Path) -> list[str]:
    """One command line of ``kind``."""
    if kind == "flags":
        command = rng.choice(list(COMMANDS))
        base, flags = COMMANDS[command]
        args = [command, *(a.format(**files) for a in base)]
        args += ["--runs", "1", "--workers", "1", "--no-progress"] if command in RUNS_ONE else []
        for _ in range(rng.choice((1, 1, 2))):
            flag = rng.choice(flags)
            args += [flag, rng.choice(FLAG_VALUES.get(flag, ()) + EDGE_FLAGS)]
        return [*args, "--out", str(out)]
    scenario = rng.choice(list(keys))
    sets = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        key, default = rng.choice(keys[scenario])
        value = near_default(default, rng) if rng.random() < 0.6 else None
        sets += ["--set", f"{key}={value if value is not None else rng.choice(EDGE_VALUES)}"]
    if kind == "set":
        est = rng.choice(("infoset", "ekf", "ukf", "box", "zonotope", "ellipsoid", "hinf", "pf"))
        noise = rng.choice(("random", "game", "bias", "targeted"))
    else:
        est = rng.choice(("perfect", "ukf", "box", "zonotope", "ellipsoid"))
        noise = rng.choice(("none", "random", "game"))
    command = "attitude" if kind == "attitude" else "intercept"
    # a quarter of the attitude cases compare the sets with the exact set instead, chosen
    # from what was drawn (the draws that follow are the same either way)
    if kind == "attitude" and zlib.crc32(" ".join(sets).encode()) % 4 == 0:
        times = ("0.1", "0.5", "0.1,1", "2")[zlib.crc32(scenario.encode()) % 4]
        args = ["attitude-tightness", scenario.format(**files), "--times", times,
                "--estimators", est if est in ("box", "zonotope", "ellipsoid") else "box",
                "--noise", noise]  # fmt: skip
        return [*args, "--out", str(out), *sets]
    args = [command, scenario.format(**files), "--runs", "1", "--workers", "1",
            "--no-progress", "--estimators", est, "--noise", noise]  # fmt: skip
    return [*args, "--out", str(out), *sets]


def run(args: list[str], limit_s: int) -> tuple[str, str]:
    """``(outcome, detail)``: ``ok``, ``refused`` (one line, status 2), ``runs failed``
    (status 1, reported: a run over ``--run-cpu-limit-s``, or one that cannot go on,
    ``REPORTED``), ``slow`` (over the limit) or
    ``FAILED`` (raised, or another status or more lines)."""
    from kalman_vs_infoset.experiments.cli import main

    out, err = io.StringIO(), io.StringIO()
    limit = TimeLimit(limit_s)
    try:
        with limit, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(args)
            except SystemExit as exc:  # argparse
                code = exc.code
    except Exception:  # noqa: BLE001 - what a user would see
        return "FAILED", traceback.format_exc()
    if limit.fired:  # whatever the cut became (a failed run, numba's SystemError)
        return "slow", ""
    text = err.getvalue()
    lines = [ln for ln in text.strip().splitlines() if ln.strip() and not ln.startswith(" ")]
    lines = [ln for ln in lines if not ln.startswith("usage:")]  # argparse's usage, then one
    if code == 0:
        return "ok", ""
    if code == 2 and len(lines) == 1 and "Traceback" not in text:
        return "refused", lines[0]
    reasons = re.findall(r"run \d+ failed: (\w+: .*)", text)

    def reported(reason: str) -> bool:
        # (a run failing otherwise under a memory limit says so in its reason)
        under_limit = reason.endswith("--run-memory-limit-mb)")
        return reason.split(":")[0] in LIMITS or reason.startswith(REPORTED) or under_limit

    if code == 1 and "Traceback" not in text and reasons and all(map(reported, reasons)):
        return "runs failed", lines[-1]  # reported: a limit, or a run that cannot go on
    return "FAILED", f"exit status {code}, {len(lines)} lines:\n{text[-3000:]}"


def search(cases: int, seed: int, kinds: tuple[str, ...], limit_s: int) -> Counter:
    """Run ``cases`` command lines; print each failure with its command line."""
    rng = random.Random(seed)
    tmp = Path(tempfile.mkdtemp(prefix="fuzz_inputs-"))
    files = {"short": tmp / "short.toml", "tiny": tmp / "tiny_rw.toml"}
    files["short"].write_text(SHORT, encoding="utf-8")
    files["tiny"].write_text(TINY_RW, encoding="utf-8")
    keys = {kind: field_keys(kind) for kind in kinds if kind != "flags"}
    counts: Counter = Counter()
    for case in range(cases):
        kind = kinds[case % len(kinds)]
        args = draw(kind, rng, keys.get(kind), files, tmp / f"out{case}")
        outcome, detail = run(args, limit_s)
        counts[outcome] += 1
        if outcome == "FAILED":
            print(f"FAILED: kvi {' '.join(repr(a) if ' ' in a else a for a in args)}\n{detail}")
    return counts


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=300, help="command lines to run")
    parser.add_argument("--seed", type=int, default=1, help="seed of the draws")
    parser.add_argument("--kinds", default="set,attitude,flags", help="set, attitude, flags")
    parser.add_argument("--limit-s", type=int, default=60, help="a command's CPU-time limit, s")
    args = parser.parse_args()
    counts = search(args.cases, args.seed, tuple(args.kinds.split(",")), args.limit_s)
    print(dict(counts))
    return 1 if counts["FAILED"] else 0


if __name__ == "__main__":
    sys.exit(main())
