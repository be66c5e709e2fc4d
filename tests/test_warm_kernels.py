"""A first run compiles the kernels in two processes side by side
(:mod:`kalman_vs_infoset.experiments.warm`): the helper's kernels are then loaded from the
cache, its compilations counted in the notice; a stopped command stops the helper, and a
failed helper costs nothing but time. Toy kernel modules (a fraction of a second to
compile) stand for the package's two groups."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest
from kalman_vs_infoset.experiments import warm

_TOY = """
import os, sys, time
from numba import njit

@njit(cache=True)
def kernel(x):
    return x * {factor} + 1.0

def warm_up():
    if {fail_in_helper} and __name__ in sys.argv:  # the helper's arguments name it
        raise RuntimeError("the helper fails")
    if {sleep_s}:
        time.sleep({sleep_s})
    if {interrupt}:
        raise KeyboardInterrupt
    assert kernel(1.0) == {factor} + 1.0
"""

_PARENT = """
import json, sys
from kalman_vs_infoset._numba_cache import CompileNotice
notice = CompileNotice("toy").install()
from kalman_vs_infoset.experiments.warm import warm_kernels
warm_kernels((("toy_first",), ("toy_aside",)), aside=True)
import toy_first, toy_aside
stats = {m.__name__: [len(m.kernel.stats.cache_hits), len(m.kernel.stats.cache_misses)]
         for m in (toy_first, toy_aside)}
print(json.dumps(stats))
notice.report()
"""


def _toys(folder, monkeypatch, first=None, **aside) -> None:
    """``toy_first`` (this process's group) and ``toy_aside`` (the helper's), written to
    ``folder``; ``first`` and ``aside`` set their behaviour. Each test's modules are its
    own (taken out of ``sys.modules`` after it)."""
    plain = {"fail_in_helper": False, "sleep_s": 0, "interrupt": False}
    (folder / "toy_first.py").write_text(_TOY.format(factor=2.0, **{**plain, **(first or {})}))
    (folder / "toy_aside.py").write_text(_TOY.format(factor=3.0, **{**plain, **aside}))
    for name in ("toy_first", "toy_aside"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.setenv("PYTHONPATH", str(folder))


def _helpers_started(monkeypatch) -> list:
    """The helper processes :func:`warm.warm_kernels` starts, as they start."""
    started: list = []
    real = warm._start_helper
    monkeypatch.setattr(warm, "_start_helper", lambda m: started.append(real(m)) or started[-1])
    return started


def test_the_helper_compiles_its_group_into_the_cache_and_this_process_loads_it(
    tmp_path, monkeypatch
):
    _toys(tmp_path, monkeypatch)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    r = subprocess.run(
        [sys.executable, "-c", _PARENT], capture_output=True, text=True, env=env, timeout=300,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    # the first group compiled here (a miss), the helper's loaded from the cache (a hit)
    assert json.loads(r.stdout.strip().splitlines()[-1]) == {
        "toy_first": [0, 1],
        "toy_aside": [1, 0],
    }
    lines = r.stderr.strip().splitlines()
    assert lines[0].startswith("toy: compiling numba kernels"), r.stderr
    assert lines[-1].startswith("toy: compiled the numba kernels in ")
    assert "(2 compilations, 1 of them in a helper process;" in lines[-1], lines[-1]


def test_a_stopped_warm_up_stops_the_helper(tmp_path, monkeypatch):
    """Ctrl-C while this process compiles its group: the helper (here a minute from
    done) is killed at once, not left compiling."""
    _toys(tmp_path, monkeypatch, first={"interrupt": True}, sleep_s=60)
    started = _helpers_started(monkeypatch)
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        warm.warm_kernels((("toy_first",), ("toy_aside",)), aside=True)
    assert time.monotonic() - t0 < 30
    (helper,) = started
    assert helper.poll() is not None and helper.returncode < 0  # killed, and reaped


def test_a_failed_helper_leaves_its_group_to_this_process(tmp_path, monkeypatch):
    _toys(tmp_path, monkeypatch, fail_in_helper=True)
    started = _helpers_started(monkeypatch)
    warm.warm_kernels((("toy_first",), ("toy_aside",)), aside=True)
    (helper,) = started
    assert helper.returncode == 1  # it failed; the group's warm-up ran here, and passed
    import toy_aside

    assert toy_aside.kernel(1.0) == 4.0


@pytest.mark.parametrize(
    ("cpus", "cached", "aside"),
    [(2, False, True), (1, False, False), (2, True, False), (2, None, False)],
)
def test_the_helper_starts_only_when_the_kernels_compile_and_a_cpu_is_free(
    cpus, cached, aside, monkeypatch
):
    from kalman_vs_infoset.experiments import progress

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cpus)))
    monkeypatch.setattr(progress, "compiled_kernels_cached", lambda: cached)
    assert warm._first_compile() is aside


def test_the_groups_are_the_package_s_warm_ups():
    """Every module named has a warm-up, and the groups name the four the pool's parent
    loads (the node set's, the slabs', the kinematic bound's and the truth's)."""
    import importlib

    names = [m for group in warm.WARM_UPS for m in group]
    assert len(names) == len(set(names)) == 4
    for name in names:
        assert callable(importlib.import_module(name).warm_up), name
