"""Limits of one run: CPU time (``--run-cpu-limit-s``) and memory
(``--run-memory-limit-mb``). A run over either is recorded as failed, with the reason,
and the other runs go on; a rerun runs it again (with a larger limit, say).

The limit is the process's CPU time (``setitimer(ITIMER_PROF)``, user + system), not the
wall clock, so it does not depend on how loaded the machine is. When it expires,
:class:`RunTimeout` is raised inside the run; it derives from ``BaseException`` so that
no ``except Exception`` inside a simulation swallows it, and it is raised again every
:data:`REPEAT_S` of CPU time until the run has stopped. A chunk of several runs gets
the limit times its length; a chunk over it is run again one run at a time, so each run
is judged by its own cost. Signals reach only a process's main thread: in a thread (a
Dask worker's, for one) the runs are not limited.

The memory limit is the growth of the process's data segment during the run
(``RLIMIT_DATA``, which on Linux counts the heap and private memory maps: numpy's and
numba's arrays), set above what the process holds when the run starts and restored
after it. An allocation over it raises ``MemoryError`` in the run, and the run fails
instead of the machine's out-of-memory killer ending the worker (and every run it
held). A process-wide limit would cap the other threads' runs too, so it is set in a
process's main thread only, on Linux only (elsewhere the option is refused).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from kalman_vs_infoset.experiments.errors import causes

try:
    import resource
except ImportError:  # not on Windows: the memory limit is refused there
    resource = None  # type: ignore[assignment]

#: CPU time between repeated timeouts of a run that has not stopped yet (s)
REPEAT_S = 0.5

Pairs = list[tuple[int, dict[str, Any]]]

#: where the memory limit can be set (RLIMIT_DATA counts memory maps on Linux >= 4.7)
MEMORY_LIMIT_SUPPORTED = sys.platform.startswith("linux") and resource is not None


@dataclass(frozen=True)
class RunLimits:
    """What one run may use (None: no limit)."""

    cpu_s: float | None = None  #: CPU time (user + system), s
    memory_mb: float | None = None  #: growth of the data segment during the run, MiB

    def __bool__(self) -> bool:
        return self.cpu_s is not None or self.memory_mb is not None


class RunTimeout(BaseException):
    """A run used more CPU time than its limit."""


def _expired(signum, frame) -> None:
    raise RunTimeout


def reraise_timeout(exc: BaseException) -> None:
    """Raise the :class:`RunTimeout`, or the command's stop (Ctrl-C, SIGTERM: a
    ``KeyboardInterrupt``), behind ``exc``, if there is one. A signal that lands while
    a compiled (numba) kernel returns comes back as a ``SystemError`` ("returned a
    result with an exception set") caused by it; a run's own ``except Exception``
    must not record that as the run's error."""
    for cur in causes(exc):
        if isinstance(cur, RunTimeout | KeyboardInterrupt):
            raise cur


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


def _data_segment_bytes() -> int | None:
    """The process's data segment now (``VmData``: what ``RLIMIT_DATA`` limits)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmData:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


#: the process that loaded them (:func:`_load_before_limit`; a forked worker loads its own)
_LOADED_PID: int | None = None


def _load_before_limit() -> None:
    """Allocate the BLAS work buffers and import the libraries runs import on first use,
    once per process, before a memory limit is set.

    OpenBLAS (numpy's) allocates its buffers at its first call of each size class, on every
    thread it uses, and when an allocation fails it does not raise: it prints
    "Memory allocation still failed after 10 retries, giving up" and ends the process.
    Under a memory limit that first call would end the command, not fail the run; after
    this, the buffers are part of the process's memory before the limit is set."""
    global _LOADED_PID
    if _LOADED_PID == os.getpid():
        return
    import numpy as np

    a = np.full((256, 256), 1e-3)  # large enough for the multithreaded paths
    np.linalg.cholesky(a @ a.T + np.eye(256))
    np.linalg.solve(a + np.eye(256), a[:, 0])
    # and the libraries a run imports on its first use of an estimator (the Kalman filters'
    # filterpy, which imports scipy.stats): an import under a small limit can crash
    # CPython itself, not raise
    import filterpy.kalman  # noqa: F401
    import scipy.optimize  # noqa: F401
    import scipy.stats  # noqa: F401
    import shapely  # noqa: F401 - the section sets' polygons

    _LOADED_PID = os.getpid()


@contextmanager
def memory_limit(mb: float | None) -> Iterator[None]:
    """Let the block grow the data segment by at most ``mb`` MiB: an allocation over it
    raises ``MemoryError`` (nothing when ``mb`` is None, outside the main thread or
    where the limit cannot be set)."""
    main = threading.current_thread() is threading.main_thread()
    if mb is not None and main and MEMORY_LIMIT_SUPPORTED:
        _load_before_limit()
    now = None if mb is None or not main or not MEMORY_LIMIT_SUPPORTED else _data_segment_bytes()
    if mb is None or now is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    cap = now + int(mb * 2**20)
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))


def _noted(row: dict[str, Any], limits: RunLimits) -> dict[str, Any]:
    """A run that failed under a memory limit says so: an allocation over the limit
    inside a library (an import, a C extension) can fail as an ``OSError`` or even a
    ``SystemError`` instead of a ``MemoryError``."""
    if row.get("status") != "failed" or "--run-memory-limit-mb" in str(row.get("error")):
        return row
    note = f" (under the memory limit of {limits.memory_mb:g} MiB a run, --run-memory-limit-mb)"
    return {**row, "error": f"{row.get('error')}{note}"}


def limited(task: Callable[[list[int]], Pairs], limits: RunLimits, runs: list[int]) -> Pairs:
    """``task(runs)`` under ``limits`` per run; a run over one comes back as a failed row
    with the reason (picklable with :func:`functools.partial`)."""
    t0 = time.perf_counter()
    n = len(runs)
    cpu = None if limits.cpu_s is None else limits.cpu_s * n
    mem = None if limits.memory_mb is None else limits.memory_mb * n
    try:
        with cpu_limit(cpu), memory_limit(mem):
            pairs = task(runs)
        return pairs if limits.memory_mb is None else [(j, _noted(r, limits)) for j, r in pairs]
    except RunTimeout:
        error = f"RunTimeout: over the CPU-time limit of {limits.cpu_s:g} s a run"
        error += " (--run-cpu-limit-s)"
    except MemoryError as exc:
        if limits.memory_mb is None:
            raise  # a resource, not the run: the runner reports it
        why = str(exc).splitlines()[0] if str(exc) else "an allocation failed"
        error = f"MemoryError: over the memory limit of {limits.memory_mb:g} MiB a run "
        error += f"(--run-memory-limit-mb): {why}"
    if n > 1:  # judge each run by its own cost
        return [pair for j in runs for pair in limited(task, limits, [j])]
    return [(runs[0], {"status": "failed", "error": error, "wall_s": time.perf_counter() - t0})]
