"""A CPU-time limit per run (``--run-cpu-limit-s``): a run over it is recorded as failed.

The limit is the process's CPU time (``setitimer(ITIMER_PROF)``, user + system), not the
wall clock, so it does not depend on how loaded the machine is. When it expires,
:class:`RunTimeout` is raised inside the run; it derives from ``BaseException`` so that
no ``except Exception`` inside a simulation swallows it, and it is raised again every
:data:`REPEAT_S` of CPU time until the run has stopped. A chunk of several runs gets
the limit times its length; a chunk over it is run again one run at a time, so each run
is judged by its own cost. Signals reach only a process's main thread: in a thread (a
Dask worker's, for one) the runs are not limited.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

#: CPU time between repeated timeouts of a run that has not stopped yet (s)
REPEAT_S = 0.5

Pairs = list[tuple[int, dict[str, Any]]]


class RunTimeout(BaseException):
    """A run used more CPU time than its limit."""


def _expired(signum, frame) -> None:
    raise RunTimeout


def reraise_timeout(exc: BaseException) -> None:
    """Raise the :class:`RunTimeout` behind ``exc``, if there is one. A timeout that
    fires while a compiled (numba) kernel returns comes back as a ``SystemError``
    ("returned a result with an exception set") caused by it; a run's own ``except
    Exception`` must not record that as the run's error."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, RunTimeout):
            raise cur
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__


@contextmanager
def cpu_limit(seconds: float | None) -> Iterator[None]:
    """Raise :class:`RunTimeout` in the block once it has used ``seconds`` of CPU time
    (nothing when ``seconds`` is None or outside the main thread)."""
    main = threading.current_thread() is threading.main_thread()
    if seconds is None or not main or not hasattr(signal, "setitimer"):
        yield
        return
    before = signal.signal(signal.SIGPROF, _expired)
    signal.setitimer(signal.ITIMER_PROF, seconds, REPEAT_S)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        signal.signal(signal.SIGPROF, before)


def limited(task: Callable[[list[int]], Pairs], limit_s: float, runs: list[int]) -> Pairs:
    """``task(runs)`` under a CPU limit of ``limit_s`` per run; a run over it comes back
    as a failed row with the reason (picklable with :func:`functools.partial`)."""
    t0 = time.perf_counter()
    try:
        with cpu_limit(limit_s * len(runs)):
            return task(runs)
    except RunTimeout:
        if len(runs) > 1:  # judge each run by its own cost
            return [pair for j in runs for pair in limited(task, limit_s, [j])]
    error = f"RunTimeout: over the CPU-time limit of {limit_s:g} s a run (--run-cpu-limit-s)"
    return [(runs[0], {"status": "failed", "error": error, "wall_s": time.perf_counter() - t0})]
