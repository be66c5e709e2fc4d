"""The costs ``kvi bench`` measures in other processes (:mod:`.cmd_bench`): starting
the command line, the Monte Carlo throughput of a worker pool with its workers' peak
memory, and the first run's compilation on an empty numba cache. CPU time throughout
(this process's and its children's, through ``resource.getrusage``), so that the
numbers hold on a busy host.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from kalman_vs_infoset.experiments.usage import cpu_s as _cpu_s
from kalman_vs_infoset.experiments.usage import peak_rss_mb

#: one Fig. 3 engagement in a fresh process, for the first-run compilation time
_FIRST_RUN = """
import json, resource, sys, time
import numpy as np
from kalman_vs_infoset._numba_cache import CompileNotice
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.intercept import run_engagement
notice = CompileNotice("bench", stream=sys.stderr).install()
sc = load_scenario(sys.argv[1])
run_engagement(sc, registry.reference("intercept").name, "random", np.random.default_rng(1))
r = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"compile_s": notice.cpu_s, "cpu_s": r.ru_utime + r.ru_stime}))
"""


def help_cpu_s(commands, repeat: int = 3) -> dict[str, float]:
    """CPU time (s) of ``kvi CMD --help`` for each of ``commands`` ("" for ``kvi
    --help``), each in a fresh interpreter, the median of ``repeat`` starts: what
    starting the command line costs (one start moves by half on a busy host: 0.55
    CPU-s once where repeats read 0.3)."""
    out = {}
    for cmd in commands:
        times = []
        for _ in range(repeat):
            before = _cpu_s()
            subprocess.run(
                [sys.executable, "-m", "kalman_vs_infoset", *([cmd] if cmd else []), "--help"],
                capture_output=True, check=True, timeout=600,
            )  # fmt: skip
            times.append(_cpu_s() - before)
        out[cmd or "(none)"] = float(np.median(times))
    return out


def _peak_rss_mb(pids) -> float:
    """The largest peak resident memory (MB) of live processes (Linux ``VmHWM``);
    NaN where /proc is not there."""
    peaks = []
    for pid in pids:
        try:
            text = Path(f"/proc/{pid}/status").read_text()
        except OSError:
            continue
        for line in text.splitlines():
            if line.startswith("VmHWM:"):
                peaks.append(float(line.split()[1]) / 1024.0)
    return max(peaks) if peaks else float("nan")


def throughput(sc, name: str, runs: int, workers: int, chunk: int = 1) -> dict[str, float]:
    """Monte Carlo runs of ``sc`` (random noise) with the estimator ``name`` on a pool
    of ``workers`` processes, ``chunk`` runs a task: runs per second (wall), runs per
    CPU-second (this process and the workers, which are waited for before the clock
    stops) and the workers' largest peak memory."""
    from kalman_vs_infoset.experiments.executors import make_executor
    from kalman_vs_infoset.experiments.intercept_runs import run_experiment

    with tempfile.TemporaryDirectory() as tmp, make_executor(workers) as pool:
        wall0, cpu0 = time.perf_counter(), _cpu_s()
        run_experiment(
            sc, name, "random", runs, 1, Path(tmp), workers=workers, progress=False,
            executor=pool, chunk=chunk,
        )  # fmt: skip
        rss = _peak_rss_mb(getattr(pool, "_processes", {}) or {})
        pool.shutdown(wait=True)  # the workers' CPU time counts once they are waited for
        wall, cpu = time.perf_counter() - wall0, _cpu_s() - cpu0
    if not np.isfinite(rss):
        rss = peak_rss_mb(children=True)
    return {"runs_per_s": runs / wall, "runs_per_cpu_s": runs / cpu, "peak_rss_mb": rss}


def first_run_compile(scenario: Path, code: str = _FIRST_RUN) -> dict[str, float]:
    """Run ``code`` (by default one Fig. 3 engagement) in a fresh process on an empty
    numba cache (a temporary ``NUMBA_CACHE_DIR``); its JSON line: ``compile_s`` (CPU
    time of the compilations, from numba's compile events) and ``cpu_s`` (the whole
    process)."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        out = subprocess.run(
            [sys.executable, "-c", code, str(scenario)],
            capture_output=True, text=True, env=env, check=True, timeout=3600,
        )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])
