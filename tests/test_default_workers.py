"""The default worker count is the CPUs the command may run on (its affinity mask on
Linux: a batch job's or a container's allotment), not the machine's CPU count, which
put one worker per CPU of a large node on the few CPUs a job was given."""

from __future__ import annotations

import os
from contextlib import contextmanager

import pytest
from kalman_vs_infoset.experiments import executors, usage


def _task(runs: list[int]) -> list[tuple[int, dict]]:
    return [(j, {"status": "ok", "error": ""}) for j in runs]


class _Job:
    chunk, task = 1, staticmethod(_task)


def _workers_started(monkeypatch, runs: int, workers=None) -> int:
    """The worker count ``executors.results`` starts for ``runs`` one-run chunks
    (the pool itself replaced by this process)."""
    seen: list[int] = []

    @contextmanager
    def pool(executor, n, scheduler):
        seen.append(n)
        yield None

    monkeypatch.setattr(executors, "executor_or", pool)
    monkeypatch.setattr(executors, "_pooled", lambda ex, task, chunks, window, lost: [])
    list(executors.results(_Job(), list(range(runs)), None, workers, None))
    return seen[0] if seen else 1


@pytest.mark.skipif(not hasattr(os, "sched_getaffinity"), reason="no affinity mask here")
def test_the_default_is_the_affinity_mask_not_the_machine(monkeypatch):
    monkeypatch.setattr(os, "cpu_count", lambda: 64)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {4, 5, 6})
    assert usage.usable_cpus() == 3
    assert _workers_started(monkeypatch, runs=50) == 3
    assert _workers_started(monkeypatch, runs=2) == 2  # never more than the chunks
    assert _workers_started(monkeypatch, runs=50, workers=8) == 8  # asked for: as asked


def test_without_an_affinity_mask_the_machine_s_cpus(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 6)
    assert usage.usable_cpus() == 6
    monkeypatch.setattr(os, "cpu_count", lambda: None)  # undeterminable: one
    assert usage.usable_cpus() == 1
