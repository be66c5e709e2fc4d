"""Random attitude scenarios within the fields' bounds, each run by every attitude set
family: the truth must be inside the set at every step (not collected by pytest: a
tool, like ``fuzz_scenarios.py`` for the intercept).

Each case changes a bundled scenario: the reaction-wheel turns (``smallsat_rw``'s PD,
``lqr_large_angle``'s LQR; inertia scaled by 0.1 to 10 with its axes' ratios drawn,
control period 0.01 to 0.2 s, a short turn), the gyrostat (its moments scaled by 0.1
to 10, the rotors' kept), measurement bounds 1e-4 to 0.1 deg and 1e-5 to 0.01 deg/s, the
disturbance bound 1e-6 to 1e-2 N m (reaction wheels), or Resurs-P's gyrodine turn (the
energy-saving law or the Euler-axis turn, a 20 to 60 s turn at a step of 0.05 to 0.2 s,
error standard deviations 1e-5 to 1e-3 rad and 3e-7 to 3e-5 rad/s, the random
disturbance none or up to 1e-2 N m, the adversary's 1e-3 to 0.1 N m); then a noise
(random, game).
Every registered attitude set estimator runs it (two runs, numpy warnings as errors);
run 0 of each is also compared with the exact set at ten control periods (``kvi
attitude-tightness``'s comparison: the exact interval outside a set's hull is a fault).
A run whose closed loop diverged is counted, not a fault (the sets must still hold the
truth up to it); a run that failed or a step outside is a fault. Scenarios the
validation refuses are counted, not run. Exit status 1 on a fault.

    python tests/fuzz_attitude.py --seconds 600 --seed 1
"""

from __future__ import annotations

import argparse
import random
import sys
import time
import warnings
from collections import Counter
from typing import Any

SCENARIOS = ("smallsat_rw", "lqr_large_angle", "gyrostat_game", "resurs_p")
NOISES = ("random", "game")


def set_estimators() -> list[str]:
    """The registered attitude estimators that are neither a Kalman baseline nor the
    measurement read as the state: the set families (box, zonotope, ellipsoid)."""
    from kalman_vs_infoset.estim import registry

    names = registry.names("attitude")
    return [n for n in names if not {"baseline", "exact"} & set(registry.get("attitude", n).roles)]


def draw_case(rng: random.Random) -> tuple[str, str | None, str, dict[str, Any]]:
    """``(scenario, controller (None: the scenario's), noise, keyword tables of
    run_attitude)``."""
    scenario, noise = rng.choice(SCENARIOS), rng.choice(NOISES)
    if scenario == "resurs_p":
        dt = rng.choice((0.05, 0.1, 0.2))
        turn = round(rng.uniform(20.0, 60.0) / dt) * dt
        dist = rng.choice((0.0, 10 ** rng.uniform(-4.0, -2.0)))
        errors = {"angle_std_rad": 10 ** rng.uniform(-5.0, -3.0),
                  "rate_std_radps": 10 ** rng.uniform(-6.5, -4.5), "disturbance_std_Nm": dist,
                  "game_disturbance_Nm": 10 ** rng.uniform(-3.0, -1.0)}  # fmt: skip
        return scenario, rng.choice(("energy", "euler")), noise, {
            "dt_s": dt, "duration_s": turn, "horizon_s": turn, "tables": {"noise": errors},
        }  # fmt: skip
    scale = 10 ** rng.uniform(-1.0, 1.0)
    angle, rate = 10 ** rng.uniform(-4.0, -1.0), 10 ** rng.uniform(-5.0, -2.0)
    if scenario == "gyrostat_game":
        sim = {"horizon_factor": 1.01, "meas_angle_deg": angle, "meas_rate_degps": rate}
        return scenario, None, noise, {
            "gyrostat": {"A_kgm2": [120 * scale, 100 * scale, 80 * scale]}, "simulation": sim,
        }  # fmt: skip
    return scenario, None, noise, {
        "body": {"inertia_kgm2": [rng.uniform(0.5, 3.0) * scale for _ in range(3)]},
        "simulation": {"duration_s": 15.0, "control_period_s": rng.choice((0.01, 0.05, 0.1, 0.2))},
        "tables": {"noise": {"meas_angle_deg": angle, "meas_rate_degps": rate,
                             "disturbance_Nm": 10 ** rng.uniform(-6.0, -2.0)}},
    }  # fmt: skip


def _what(*names: str | None) -> str:
    """A case's scenario, controller (when drawn), noise and estimator, in one string."""
    return " ".join(n for n in names if n)


def run_case(case_seed: int, estimators: list[str], counts: Counter) -> list[str]:
    """The faults of one case (every estimator on the same drawn scenario)."""
    from kalman_vs_infoset.experiments.errors import InputError

    from kalman_vs_infoset import api

    scenario, controller, noise, tables = draw_case(random.Random(case_seed))
    faults = []
    for est in estimators:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                df = api.run_attitude(scenario, controller=controller, noise=noise,
                                      estimator=est, runs=2, seed=case_seed,
                                      **tables)  # fmt: skip
        except InputError:
            counts["refused"] += 1
            return faults
        counts["runs"] += len(df)
        ok = df[df["status"] == "ok"]
        counts["diverged"] += int(ok["diverged"].sum()) if "diverged" in ok else 0
        counts["steps outside"] += int(ok["truth_outside"].sum())
        if len(ok) < len(df) or ok["truth_outside"].sum() > 0:
            errors = df.loc[df["status"] != "ok", "error"].tolist()
            outside = ok["truth_outside"].tolist()
            faults.append(f"case {case_seed}: {_what(scenario, controller, noise, est)} "
                          f"{tables}: outside {outside}, errors {errors}")  # fmt: skip
    try:
        faults += exact_faults(case_seed, scenario, controller, noise, tables, estimators, counts)
    except Exception as exc:  # a fault of the case (named), not the end of the search
        faults.append(f"case {case_seed}: {_what(scenario, controller, noise)} {tables}: the "
                      f"exact comparison raised {type(exc).__name__}: {exc}")  # fmt: skip
    counts["cases"] += 1
    return faults


def _overrides(tables: dict[str, Any]) -> list[str]:
    """``run_attitude``'s keyword tables (and top-level fields) as ``--set
    [TABLE.]KEY=VALUE`` lines."""
    flat = {k: v for k, v in tables.items() if k != "tables"} | tables.get("tables", {})
    lines = []
    for name, fields in flat.items():
        if isinstance(fields, dict):
            lines += [f"{name}.{key}={value!r}" for key, value in fields.items()]
        else:  # a top-level field (the gyrodines' dt_s, duration_s, horizon_s)
            lines.append(f"{name}={fields!r}")
    return lines


def exact_faults(case_seed, scenario, controller, noise, tables, estimators, counts) -> list[str]:
    """Run 0 of each family against the exact set at ten control periods
    (``kvi attitude-tightness``'s comparison): the exact interval outside a set's hull
    beyond the linearisation's order is a fault."""
    from kalman_vs_infoset.experiments import cmd_attitude_tightness as cat

    # (the gyrostat's cases keep its scenario's period, 0.05 s; the gyrodines' step is dt_s)
    period = (
        tables["dt_s"] if "dt_s" in tables else tables["simulation"].get("control_period_s", 0.05)
    )
    args = argparse.Namespace(scenario=scenario, overrides=_overrides(tables),
                              controller=controller, noise=noise, seed=case_seed,
                              times=[10 * period], estimators=estimators)  # fmt: skip
    setup, controller, _ = cat._setup(args)
    faults = []
    for est in estimators:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            res = cat.compare(setup, controller, noise, est, case_seed, args.times)
        if res["diverged_time_s"] is not None:
            continue
        counts["exact checks"] += 1
        if not res["exact_inside"]:
            ratios = [t["ratio"] for t in res["times"]]
            faults.append(f"case {case_seed}: {_what(scenario, controller, noise, est)} "
                          f"{tables}: the exact interval outside the hull "
                          f"(ratios {ratios})")  # fmt: skip
    return faults


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=300.0, help="how long to search (s)")
    p.add_argument("--seed", type=int, default=0, help="first case's seed")
    p.add_argument("--cases", type=int, default=None, help="at most this many cases")
    args = p.parse_args(argv)
    estimators = set_estimators()
    counts: Counter = Counter()
    faults: list[str] = []
    t0, seed = time.monotonic(), args.seed
    while time.monotonic() - t0 < args.seconds and (
        args.cases is None or seed - args.seed < args.cases
    ):
        faults += run_case(seed, estimators, counts)
        seed += 1
    for fault in faults:
        print("FAULT", fault)
    print(f"{counts['cases']} cases ({counts['refused']} refused by the validation), "
          f"{counts['runs']} runs of {', '.join(estimators)}: {counts['steps outside']} steps "
          f"outside, {counts['diverged']} runs diverged, {counts['exact checks']} runs against "
          f"the exact set, {len(faults)} faults")  # fmt: skip
    return 1 if faults else 0


if __name__ == "__main__":
    sys.exit(main())
