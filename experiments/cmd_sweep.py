"""``kvi sweep SCENARIO.toml --key TABLE.KEY --values "[...]"``.

A sensitivity study: the ``compare`` experiment (estimators x noises on paired runs)
repeated for each value of one scenario field, e.g. the Kalman filters' noise
inflation, the disturbance bound ``model.nu_mps2`` or the slab set's
``estimator.infoset.split_ratio``. Each value is a ``--set KEY=VALUE`` override
(:func:`experiments.scenario.apply_overrides`): validated like the file, its runs stored
under the suffixed scenario name (so they resume, and never mix with the plain
scenario's), and every value sees the same truths (same seed, paired).

Writes a table of the summaries with a ``value`` column (markdown and CSV) and a
figure of mean miss and mean fuel against the value (one line per estimator x noise).
"""

from __future__ import annotations

import argparse
import json
import time
import tomllib
from typing import Any

from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.files import derived_write

#: the runs use the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True


def _canonical(value: Any) -> Any:
    """A value as the scenario sees it: numbers as floats (``0`` and ``0.0`` are one)."""
    if isinstance(value, list):
        return [_canonical(v) for v in value]
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return value


def _toml_values(text: str) -> list[Any]:
    try:
        values = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        values = None
    if not isinstance(values, list) or not values:
        raise argparse.ArgumentTypeError(
            f'expected a non-empty TOML array, e.g. "[1, 3, 10]"; got {text!r}'
        )
    seen = [json.dumps(_canonical(v)) for v in values]  # 0 and 0.0 are one value
    twice = sorted({json.dumps(v) for v, s in zip(values, seen, strict=True) if seen.count(s) > 1})
    if twice:  # the same value would be run and tabled twice
        raise argparse.ArgumentTypeError(f"{', '.join(twice)} given twice in {text!r}")
    return values


def add_arguments(p: argparse.ArgumentParser) -> None:
    options.add_grid(p, trace=False)  # a sweep draws no run's trace
    p.add_argument(
        "--key",
        required=True,
        help="the field to vary, TABLE.KEY or TABLE.SUBTABLE.KEY, or a comma list of fields "
        "given the same value (e.g. estimator.ekf.noise_inflation,estimator.ukf.noise_inflation)",
    )
    p.add_argument(
        "--values",
        required=True,
        type=_toml_values,
        help='its values as a TOML array, e.g. "[1, 3, 10, 30]" or "[[57.0, 59.0], [57.5, 58.5]]"',
    )


#: tables whose fields no value of a sweep can change: a key there was taken and ignored
#: (every value had the same rows)
UNSWEPT = {
    "experiment": "every value runs the same paired runs: set them with --runs, --seed, "
    "--noise and --estimators (or sweep the seed by running the command once per --seed)",
    "reference": "the paper's printed numbers, which no run reads",
}


def _keys(text: str, overrides: list[str]) -> list[str]:
    """The swept fields: one TABLE.KEY, or several set to the same value (a comma list,
    e.g. both Kalman filters' ``noise_inflation``)."""
    keys = [k.strip() for k in text.split(",")]
    for key in keys:
        parts = key.split(".")
        if not 2 <= len(parts) <= 3 or not all(parts):  # the keys --set takes
            raise InputError(
                f"--key {text!r}: expected TABLE.KEY or TABLE.SUBTABLE.KEY, or a comma list "
                "of them (e.g. model.nu_mps2, estimator.infoset.n_nodes)"
            )
        if parts[0] in UNSWEPT:
            raise InputError(f"--key {key}: {UNSWEPT[parts[0]]}")
    if len(set(keys)) < len(keys):
        raise InputError(f"--key {text!r}: a key given twice")
    given = {o.partition("=")[0].strip() for o in overrides}
    for key in keys:
        if key in given:  # one of the two values would be silently ignored
            raise InputError(f"--key {key} is also given with --set; give it only as --key")
    return keys


def run(args) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    import pandas as pd
    from kalman_vs_infoset.experiments import paired, plots
    from kalman_vs_infoset.experiments.intercept_runs import run_grid
    from kalman_vs_infoset.experiments.report import summary_markdown, write_text
    from kalman_vs_infoset.experiments.scenario import load_scenario, toml_value

    keys = _keys(args.key, args.overrides)
    key = ",".join(keys)
    t0 = time.perf_counter()
    # compare's folder by default: the runs' files carry the +key=value suffix and the
    # tables the key, so nothing collides
    base, runs, seed, out = options.resolve(args)
    # every value is validated before the first run starts (a refusal names the value)
    scenarios = []
    for v in args.values:
        try:
            scenarios.append(load_scenario(
                args.scenario, [*args.overrides, *(f"{k}={toml_value(v)}" for k in keys)]
            ))  # fmt: skip
        except InputError as exc:
            raise InputError(f"--values: {key} = {toml_value(v)}: {exc}") from None
    rows, frames = [], []
    for value, sc in zip(args.values, scenarios, strict=True):
        summaries, dfs = run_grid(sc, args, runs, seed, out, args.estimators, args.noise)
        rows += [{"value": json.dumps(value), **row} for row in summaries]
        frames += [df.assign(value=json.dumps(value)) for df in dfs]
    # every value sees the same truths: each one minus the first, run by run
    compared = paired.along(pd.concat(frames, ignore_index=True), "value",
                            json.dumps(args.values[0]))  # fmt: skip
    stem = f"{base.name}-sweep-{key}"
    flat = pd.json_normalize(rows, sep="_")
    csv = out / f"{stem}.csv"
    derived_write(csv, lambda tmp: flat.to_csv(tmp, index=False))
    text = summary_markdown(rows, _LABELS) + paired.section(compared)
    files = [csv, write_text(out / f"{stem}.md", text)]
    title = f"{base.name}: {key} swept, {runs} paired runs per point"
    files += plots.save(plots.sweep_figure(flat, key, title, _xlabel(keys)), out / stem)
    return {
        "scenario": base.name,
        "key": key,
        "values": args.values,
        "runs": runs,
        "rows": rows,
        "paired": compared,
        "out": str(out),
        "files": [str(f) for f in files],
        "wall_s": time.perf_counter() - t0,
    }


_LABELS = ("value", "estimator", "noise")


def _xlabel(keys: list[str]) -> str:
    """The figure's x label: the keys and their field's doc with its unit (one doc when
    the fields given the same value share it, e.g. both filters' noise inflation)."""
    from kalman_vs_infoset.experiments.scenario import field_doc

    docs = list(dict.fromkeys(d for d in map(field_doc, keys) if d))
    return ", ".join(keys) + (f"\n{'; '.join(docs)}" if docs else "")


def render(result: dict[str, Any]) -> str:
    from kalman_vs_infoset.experiments import paired
    from kalman_vs_infoset.experiments.report import summary_markdown

    return (
        f"{result['key']} swept over {result['values']}\n"
        + summary_markdown(result["rows"], _LABELS)
        + paired.section(result.get("paired"))
        + "files:\n"
        + "\n".join("  " + f for f in result["files"])
    )
