"""Random extreme sequences through the intercept set estimators, their compiled kernels
checked for out-of-bounds access (not collected by pytest: a tool, like
``stress_interrupts.py``).

Each case draws a prior box (offsets from 1 mm to 1000 km, rates, ranges, a closing
speed interval or none), then up to 400 steps of bearings, ranges, extremes,
containment tests and predictions with random steps and impulses, until the set
empties. The process re-runs itself with ``NUMBA_BOUNDSCHECK=1`` (and a cache folder
of its own, since numba's cache does not tell the bounds-checked compilation apart):
an access past a buffer raises ``IndexError`` instead of corrupting memory. Counts
the cases, the out-of-bounds accesses and any other error; exit status 1 if any.

    python tests/fuzz_set_kernels.py --seconds 900 --seed 20000
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter

import numpy as np


def _case(rng: np.random.Generator, name: str) -> str:
    """One random sequence; the final status of the belief."""
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.estim.intercept import model as im
    from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss

    model = im.ChannelModel()
    y, v = 10 ** rng.uniform(-3, 6), 10 ** rng.uniform(-4, 3)
    x0 = 10 ** rng.uniform(5, 6.9)
    speed = None
    if rng.random() < 0.5:
        e = 58e3 * rng.uniform(0.5, 1.5)
        speed = (e, e * (1 + 10 ** rng.uniform(-6, -0.5)))
    y_hi = y * rng.uniform(-1, 1) if rng.random() < 0.3 else y
    prior = im.ChannelPrior((-y, y_hi), (-v, v), (x0, x0 * (1 + rng.uniform(0, 0.5))), speed)
    est = registry.get("intercept", name).build(None, im.ChannelSetting(model, speed))
    b = est.initial(prior)
    for _ in range(int(rng.integers(5, 400))):
        if rng.random() < 0.6:
            b = est.update(b, im.Bearing(float(rng.normal() * 10 ** rng.uniform(-9, -3.5))))
        elif rng.random() < 0.4:
            off = float(rng.uniform(0, 0.01))
            b = est.update(b, im.Range(float(x0 * rng.uniform(0.0, 1.5)), off_axis_rad=off))
        if b.is_empty:
            break
        if rng.random() < 0.5:
            b.extremes(MissForecast(model))
            b.extremes(ZeroEffortMiss(model))
        if rng.random() < 0.2:
            b.attained(MissForecast(model))
        if rng.random() < 0.3:
            state = [rng.normal() * 1e-3, rng.normal() * 1e-5, x0 * rng.uniform(0.5, 1.5)]
            b.contains(np.array(state))
        dt = 10 ** rng.uniform(-1.5, 0.5) if rng.random() < 0.95 else 10 ** rng.uniform(0.5, 1.7)
        u = None
        if rng.random() < 0.5:
            k = float(rng.normal() * 10 ** rng.uniform(-2, 2))
            u = im.Impulse(k, float(10 ** rng.uniform(-4, 1))) if rng.random() < 0.5 else k
        b = est.predict(b, float(dt), u)
        if b.is_empty:
            break
    return str(b.status)


def _fuzz(seconds: float, seed: int, names: list[str]) -> int:
    statuses: Counter = Counter()
    errors: Counter = Counter()
    out_of_bounds = 0
    end, i = time.monotonic() + seconds, 0
    while time.monotonic() < end:
        name = names[i % len(names)]
        try:
            statuses[(name, _case(np.random.default_rng(seed + i), name))] += 1
        except IndexError as exc:  # numba's bounds check
            out_of_bounds += 1
            print(f"out of bounds: {name} case {seed + i}: {exc}", flush=True)
        except Exception as exc:  # noqa: BLE001 - counted and shown, the search goes on
            errors[(name, type(exc).__name__, str(exc)[:80])] += 1
            print(f"error: {name} case {seed + i}: {type(exc).__name__}: {exc}", flush=True)
        i += 1
    print(f"{i} cases, {out_of_bounds} out-of-bounds accesses, {sum(errors.values())} errors")
    for (name, status), count in sorted(statuses.items()):
        print(f"  {name:10s} ended {status:13s} {count}")
    return 1 if out_of_bounds or errors else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=600.0, help="how long to search (s)")
    p.add_argument("--seed", type=int, default=20000, help="first case's seed")
    p.add_argument("--estimators", default="infoset,ellipsoid,zonotope,box")
    p.add_argument("--no-boundscheck", action="store_true", help="the regular compilation")
    args = p.parse_args()
    if not args.no_boundscheck and os.environ.get("NUMBA_BOUNDSCHECK") != "1":
        with tempfile.TemporaryDirectory() as cache:
            # without LLVM's passes: compiles faster, and no check is optimised away
            env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_OPT": "0",
                   "NUMBA_CACHE_DIR": cache}  # fmt: skip
            return subprocess.run([sys.executable, *sys.argv], env=env).returncode
    return _fuzz(args.seconds, args.seed, args.estimators.split(","))


if __name__ == "__main__":
    sys.exit(main())
