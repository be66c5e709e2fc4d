"""CPU time and peak memory of a command and of the worker processes it started.

A Monte Carlo command reports, beside its wall time, the CPU time its runs took
(``cpu_s``: this process and its finished worker processes, user + system) and the
largest peak resident memory of one worker (``worker_peak_rss_mb``). CPU time does not
depend on how busy a shared host is, so a study's cost measured on a small run scales to
a large one (docs/performance.md). Both come from ``getrusage``: a local pool's workers
are counted once they have exited and been waited for, which the runner does before a
variant's summary is written; the workers of a remote Dask cluster are not this
process's children, and are not counted (the command reports ``None`` then).
"""

from __future__ import annotations

import os
import resource
import sys

__all__ = ["cpu_s", "peak_rss_mb", "usable_cpus"]

# ru_maxrss is in kilobytes on Linux, in bytes on macOS
_RSS_UNIT_MB = 1.0 / (1024.0 * 1024.0) if sys.platform == "darwin" else 1.0 / 1024.0


def usable_cpus() -> int:
    """The CPUs this process may run on: its affinity mask where the system has one
    (Linux: a batch job's or a container's ``taskset``/cpuset allotment), else every
    CPU of the machine. ``os.cpu_count()`` counts the machine's: on a 4-CPU job of a
    64-CPU node the default worker count would put 64 processes on 4 CPUs, each with
    its own memory."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def cpu_s() -> float:
    """CPU time (s, user + system) of this process and of its finished, waited-for
    child processes (and theirs)."""
    total = 0.0
    for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN):
        r = resource.getrusage(who)
        total += r.ru_utime + r.ru_stime
    return total


def peak_rss_mb(children: bool = False) -> float:
    """The peak resident memory (MB) of this process, or (``children``) the largest
    peak of one of its finished, waited-for child processes (0 when there was none)."""
    who = resource.RUSAGE_CHILDREN if children else resource.RUSAGE_SELF
    return resource.getrusage(who).ru_maxrss * _RSS_UNIT_MB
