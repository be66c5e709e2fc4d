"""Random intercept scenarios within the fields' bounds, each run by every set family:
the truth must be inside the set at every checked step (not collected by pytest: a
tool, like ``fuzz_set_kernels.py``).

Each case changes kp_fig3's single engagement: the closing speed (3 to 90 km/s) and an
interval around it, a short approach (5 to 30 s) and its range box, ``eps``, the
lateral boxes (50 m to 40 km), the bearing bound's ends and reference range (the box
inside its line, sometimes ending exactly where the line meets its floor), ``nu`` up to
1 m/s^2, steps up to 12 s, the Sun's distance, the range finder, the impulses and the
reserve, a few node-set options, and a truth at a corner of the boxes with positive
probability; then a noise (random, game, bias, targeted). At every checked step the
truth must be inside the set and its zero-effort miss and miss forecast inside the
set's extremes of them. Scenarios the validation refuses are counted, not run. This
search found the bearing bound's floor inside the range box (docs/models.md §1.2),
which the validation now refuses, and (under ``kvi tightness``) a bound of the miss
between nodes lost to cancellation. Exit status 1 if a set lost the truth or a run
raised.

    python tests/fuzz_scenarios.py --seconds 900 --seed 20000
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from collections import Counter

import numpy as np
from time_limit import TimeLimit

SETS = ("infoset", "ellipsoid", "zonotope", "box")
NOISES = ("random", "game", "bias", "targeted")
#: node-set options a case may change (a few at a time), with the values it draws from
NODE_OPTIONS = {
    "n_sections": (5, 9, 29, 60), "n_nodes": (4, 6, 12, 20), "n_bands": (1, 2, 4, 8),
    "node_split_ratio": (1.2, 2.0, 4.0), "min_split_tau_s": (0.0, 0.5, 2.0),
    "tighten_rtol": (0.001, 0.01, 0.3, 1.0), "max_inserts": (0, 4, 16),
    "split_bands": ("true", "false"), "impulse_per_piece": ("true", "false"),
    "band_trials": ('"auto"', '"impulse_spread"', '"extreme_bands"'),
    "max_pieces": (1, 4, 16), "sections": ('"nodes"', '"slabs"'),
}  # fmt: skip


def draw_case(rng: np.random.Generator) -> tuple[list[str], str]:
    """``(overrides, noise)`` of one case (``--set`` overrides of kp_fig3)."""
    from kalman_vs_infoset.estim.intercept.model import BearingBound

    def pick(*values):
        return values[int(rng.integers(len(values)))]

    def corner(lo: float, hi: float) -> float:  # each end with positive probability
        return pick(lo, hi, float(rng.uniform(lo, hi)))

    e = pick(58.0, float(rng.uniform(3.0, 90.0)))
    x_lo = e * rng.uniform(5.0, 30.0)
    x_hi = x_lo * rng.uniform(1.0, 1.4)
    eps = pick(5.0, float(rng.uniform(0.2, 0.6 * x_lo)))
    y = pick(10.0, float(rng.uniform(0.05, 40.0)))
    v = pick(0.1, float(rng.uniform(0.001, 0.6)))
    spread = pick(0.0, float(rng.uniform(0.0, 0.03)))
    e_lo, e_hi = e * (1 - spread * rng.random()), e * (1 + spread * rng.random())
    b0, b1 = sorted(pick(1.5e-4, 2.3e-4, float(10 ** rng.uniform(-6, -2.5))) for _ in range(2))
    ref = x_hi * pick(rng.uniform(1.0, 3.0), rng.uniform(0.3, 1.0))
    line_km = BearingBound(b0, b1, ref * 1e3).linear_range_m / 1e3
    if line_km < x_hi:  # the box inside the line, its far edge where the line ends
        ref *= x_hi / line_km * (1 + 1e-9)
    te = corner(e_lo, e_hi)
    out = [
        f"model.closing_speed_kmps={e}", f"model.eps_km={eps}",
        f"model.nu_mps2={pick(0.005, 1e-4, rng.uniform(1e-4, 0.2), rng.uniform(0.2, 1.0))}",
        f"model.bearing_bound_start_rad={b0}", f"model.bearing_bound_end_rad={b1}",
        f"model.nominal_range_km={ref}",
        f"model.dt_s={(dt := pick(0.5, 0.25, 1.0, rng.uniform(0.05, 3.0), rng.uniform(3.0, 12.0)))}",  # noqa: E501
        f"model.sun_distance_km={pick(1.496e8, 10 ** rng.uniform(6.0, 10.0))}",
        f"estimator.x_km=[{x_lo}, {x_hi}]", f"estimator.closing_speed_kmps=[{e_lo}, {e_hi}]",
        f"estimator.vx_kmps=[{-e_hi - 1.0}, {-e_lo + 1.0}]",
        f"truth.x_km=[{(tx := corner(x_lo, x_hi))}, {tx}]", f"truth.vx_kmps=[{-te}, {-te}]",
        f"guidance.vertical={pick('true', 'false')}",
        f"guidance.reserve_mps={pick(2000.0, rng.uniform(0.0, 300.0))}",
        f"guidance.max_impulse_mps={pick(7.5, rng.uniform(0.5, 50.0))}",
        f"guidance.min_impulse_mps={pick(0.25, 0.0)}",
        f"range_finder.enabled={pick('true', 'false', 'false')}",
        f"range_finder.rel_bound={pick(0.05, rng.uniform(0.001, 0.5))}",
        # at decision steps (the scenario check refuses other times)
        f"range_finder.period_s={dt * max(1, round(pick(2.0, rng.uniform(0.1, 10.0)) / dt))}",
        f"range_finder.first_s={dt * round(pick(1.0, rng.uniform(0.0, 40.0)) / dt)}",
    ]  # fmt: skip
    for axis in ("y", "z"):
        out += [f"estimator.{axis}_km=[{-y}, {y}]", f"estimator.v{axis}_kmps=[{-v}, {v}]"]
        out += [f"truth.{axis}_km=[{(p := corner(-y, y))}, {p}]"]
        out += [f"truth.v{axis}_kmps=[{(w := corner(-v, v))}, {w}]"]
    if rng.random() < 0.5:
        keys = rng.choice(sorted(NODE_OPTIONS), size=int(rng.integers(1, 5)), replace=False)
        out += [f"estimator.infoset.{k}={pick(*NODE_OPTIONS[k])}" for k in keys]
    return out, str(pick(*NOISES))


def _run(sc, name: str, noise: str, seed: int) -> tuple[int, int, int]:
    """One engagement: ``(checked steps, steps outside the set, checked steps whose
    truth's zero-effort miss or miss forecast lies outside the set's extremes)``. The
    second oracle is the stronger one: a bound of the miss between nodes once came out
    too tight while the containment test, which takes other bounds, held the truth."""
    import pandas as pd
    from kalman_vs_infoset.experiments.sim.intercept import Engagement
    from kalman_vs_infoset.experiments.sim.trace import Recorder

    rec = Recorder(sets_every=0)
    eng = Engagement(sc, name, noise, np.random.default_rng(seed), record=rec)
    while eng.step():
        pass
    res = eng.finish()
    rows = pd.DataFrame(rec.rows)
    beyond = 0
    if len(rows):
        rows = rows[rows["checked"] & (rows["status"] == "ok")]
        for q in ("zem", "forecast"):
            true = rows[f"{q}_true_m"]
            tol = 1e-6 * (1.0 + true.abs())  # the describe_channel rounding, not a margin
            low, high = true < rows[f"{q}_lo_m"] - tol, true > rows[f"{q}_hi_m"] + tol
            beyond += int((low | high).sum())
    return res.checked_steps, res.truth_outside, beyond


def _fuzz(
    seconds: float, seed: int, names: list[str], cases: int | None = None, limit_s: int = 60
) -> int:
    from kalman_vs_infoset.experiments.errors import InputError
    from kalman_vs_infoset.experiments.scenario import load_scenario, scenario_folder

    base = scenario_folder(None) / "kp_fig3.toml"
    outside: Counter = Counter()
    errors: Counter = Counter()
    runs = refused = checked = slow = 0
    end, i = time.monotonic() + seconds, 0
    while time.monotonic() < end and (cases is None or i < cases):
        overrides, noise = draw_case(np.random.default_rng(seed + i))
        try:
            with warnings.catch_warnings():  # a drawn option another variant reads: fine
                warnings.filterwarnings("ignore", "--set .* has no effect", UserWarning)
                sc = load_scenario(str(base), overrides)
        except InputError:
            refused += 1  # the validation's work: not a fault
            i += 1
            continue
        for name in names:
            # a targeted run with the range finder can take minutes: it is cut and counted
            limit = TimeLimit(limit_s)
            try:
                with limit:
                    steps, out, beyond = _run(sc, name, noise, seed + i)
            except Exception as exc:  # noqa: BLE001 - counted and shown, the search goes on
                errors[(name, type(exc).__name__)] += 1
                print(f"error: {name} {noise} case {seed + i}: {type(exc).__name__}: {exc}")
                continue
            if limit.fired:
                slow += 1
                continue
            runs += 1
            checked += steps
            if out or beyond:
                outside[name] += 1
                print(f"outside: {name} {noise} case {seed + i}: {out} of {steps} steps outside "
                      f"the set, {beyond} outside its extremes of the miss; --set "
                      f"{' --set '.join(overrides)}")  # fmt: skip
        sys.stdout.flush()
        i += 1
    print(f"{i} cases ({refused} refused by the validation), {runs} runs ({slow} more cut at "
          f"{limit_s} CPU-s), {checked} checked "
          f"steps: {sum(outside.values())} runs lost the truth, {sum(errors.values())} "
          "raised")  # fmt: skip
    for (name, kind), count in sorted(errors.items()):
        print(f"  {name:10s} {kind} {count}")
    return 1 if outside or errors else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=600.0, help="how long to search (s)")
    p.add_argument("--seed", type=int, default=20000, help="first case's seed")
    p.add_argument("--estimators", default=",".join(SETS))
    p.add_argument("--run-limit-s", type=int, default=60, help="a run's CPU-time limit (s)")
    args = p.parse_args()
    return _fuzz(args.seconds, args.seed, args.estimators.split(","), None, args.run_limit_s)


if __name__ == "__main__":
    sys.exit(main())
