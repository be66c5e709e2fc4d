"""Stop a pooled command at random moments, many times: each must exit promptly.

Not collected by pytest: the faults it found were each seen in a few stops out of a
hundred or fewer (a hang at exit once in CI, never in 40 stops on the development
host); ``test_reliability_signals.py`` places the signal deterministically instead.
Run it by hand after touching the runner, the executors or the signal handlers
(``experiments/signals.py``)::

    .venv/bin/python tests/stress_interrupts.py --tries 50 --signal INT

Each try starts ``kvi attitude`` on two workers (``--workers``), waits for its first saved chunk,
waits a random part of a second more, sends the signal and allows ``--timeout-s`` for
the exit (status 130 for SIGINT, 143 for SIGTERM, and no traceback on stderr). A
command still running then gets SIGABRT, and every thread's stack is printed
(``PYTHONFAULTHANDLER``). With ``--within-s S`` the signal comes at a random moment of
the first ``S`` seconds instead (the command's imports, the kernels' warm-up, the
pool's start), from 0.05 s on: before that Python is still starting (its ``site``
module), and a Ctrl-C there gets Python's own traceback.
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness_texts import SLOW_RW, as_from_a_terminal

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = {"INT": 130, "TERM": 143}


def one_try(
    sig: str, delay_s: float, timeout_s: float, from_start: bool = False, workers: int = 2
) -> tuple[str, float]:
    """``("ok" | "hang" | "status N" | "traceback", seconds to exit)`` of one stopped
    command: ``delay_s`` after its first saved chunk, or after its start."""
    with tempfile.TemporaryDirectory() as tmp:
        scenario, out = Path(tmp) / "slow_rw.toml", Path(tmp) / "out"
        scenario.write_text(SLOW_RW)
        args = [sys.executable, "-m", "kalman_vs_infoset", "attitude", str(scenario),
                "--noise", "random", "--workers", str(workers), "--no-progress", "--out", str(out),
                "--runs", "800"]  # fmt: skip
        env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
        proc = subprocess.Popen(args, cwd=ROOT, stderr=subprocess.PIPE, text=True, env=env,
                                preexec_fn=as_from_a_terminal)  # fmt: skip
        deadline = time.monotonic() + 120.0
        while not from_start and not any(out.glob("*.parquet")) and proc.poll() is None:
            if time.monotonic() > deadline:
                proc.kill()
                return "no chunk saved in 120 s", 0.0
            time.sleep(0.02)
        time.sleep(delay_s)
        t0 = time.monotonic()
        proc.send_signal(getattr(signal, f"SIG{sig}"))
        try:
            _, err = proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGABRT)
            _, err = proc.communicate(timeout=30)
            print(err[-4000:], file=sys.stderr)
            return "hang", time.monotonic() - t0
        took = time.monotonic() - t0
        if proc.returncode != EXPECTED[sig]:
            print(
                f"status {proc.returncode}, signal {delay_s:.3f} s after "
                f"{'the start' if from_start else 'the first chunk'}:",
                file=sys.stderr,
            )
            print(err[-2000:], file=sys.stderr)
            return f"status {proc.returncode}", took
        if "Traceback" in err or "Exception ignored" in err:
            print(err[-2000:], file=sys.stderr)
            return "traceback", took
        return "ok", took


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tries", type=int, default=25, help="commands to stop (default 25)")
    p.add_argument("--signal", choices=sorted(EXPECTED), default="INT", help="default INT")
    p.add_argument("--timeout-s", type=float, default=15.0, help="allowed exit time, s")
    p.add_argument("--workers", type=int, default=2, help="the command's --workers (default 2)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random delays")
    p.add_argument("--within-s", type=float, default=None,
                   help="signal within this many seconds of the start (default: after "
                        "the first saved chunk)")  # fmt: skip
    args = p.parse_args(argv)
    rng = random.Random(args.seed)
    outcomes: dict[str, int] = {}
    slowest_s = 0.0
    for _ in range(args.tries):
        if args.within_s is None:
            delay_s = rng.uniform(0.0, 1.0)
            what, took_s = one_try(args.signal, delay_s, args.timeout_s, workers=args.workers)
        else:
            delay_s = rng.uniform(0.05, max(args.within_s, 0.05))
            what, took_s = one_try(args.signal, delay_s, args.timeout_s, True, args.workers)
        outcomes[what] = outcomes.get(what, 0) + 1
        slowest_s = max(slowest_s, took_s)
    print(f"{args.tries} tries (SIG{args.signal}): {outcomes}; slowest exit {slowest_s:.2f} s")
    return 0 if outcomes == {"ok": args.tries} else 1


if __name__ == "__main__":
    sys.exit(main())
