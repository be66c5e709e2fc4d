"""A time limit for the search tools (``fuzz_scenarios.py``, ``fuzz_inputs.py``).

The limit is the process's user CPU time (``setitimer(ITIMER_VIRTUAL)``, SIGVTALRM): the
commands run in the tools' own process, and a command guards SIGALRM for its signal
handling (``experiments/signals.py``) and SIGPROF for ``--run-cpu-limit-s``, so neither
is free. Raised inside a compiled kernel, the limit's exception reaches the caller as
numba's ``SystemError``, and a command records an exception in a run as a failed run:
the limit keeps a flag that tells a cut block apart from a fault, whatever came back.
"""

from __future__ import annotations

import signal


class TimeLimit:
    """``with TimeLimit(s) as limit: ...``; afterwards ``limit.fired`` says whether the
    block was cut at ``s`` CPU-seconds (the exception it raised is then swallowed)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.fired = False

    def _fire(self, signum, frame) -> None:
        self.fired = True
        raise TimeoutError(f"over the {self.seconds}-s limit")

    def __enter__(self) -> TimeLimit:
        self.fired = False
        self._previous = signal.signal(signal.SIGVTALRM, self._fire)
        signal.setitimer(signal.ITIMER_VIRTUAL, self.seconds)
        return self

    def __exit__(self, kind, exc, tb) -> bool:
        signal.setitimer(signal.ITIMER_VIRTUAL, 0.0)
        signal.signal(signal.SIGVTALRM, self._previous)
        return self.fired  # a cut block's exception, whatever it became, is the limit's
