"""Hypothesis profiles.

``ci`` (the default): derandomized, so every run of ``make test`` tries the same
examples and ``main`` stays reproducibly green or red. ``fuzz`` (``make fuzz``):
random exploration, a fresh seed per round, printed so that a failure can be
replayed with ``--hypothesis-seed``. The property tests found the holes listed in
the README under random exploration; ``make fuzz`` is how to keep looking.
"""

import os
from pathlib import Path

import pytest
from compile_kernels import compile_kernels
from harness_texts import SHORT, TINY_RW
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("fuzz", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


# Tests write only to temporary folders (`make test` used to write
# into the user's results/): every test module is checked against a snapshot of the
# repository's results/ folder taken before it ran.
_RESULTS = Path(__file__).resolve().parents[1] / "results"


def _snapshot(root: Path) -> dict[str, tuple[int, int]]:
    if not root.is_dir():
        return {}
    return {
        str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns)
        for p in root.rglob("*")
        if p.is_file()
    }


@pytest.fixture(autouse=True, scope="module")
def _results_folder_untouched(request):
    before = _snapshot(_RESULTS)
    yield
    after = _snapshot(_RESULTS)
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    if changed:
        pytest.fail(
            f"{request.module.__name__} wrote into {_RESULTS}: {changed[:3]} "
            "(tests must write only to temporary folders)"
        )


def pytest_configure(config):
    # known without pytest-xdist too (the suite also runs in one process)
    config.addinivalue_line("markers", "xdist_group(name): tests run by one xdist worker")


def _xdist_group(item) -> str | None:
    names = {m.args[0] if m.args else m.kwargs.get("name", "default")
             for m in item.iter_markers("xdist_group")}  # fmt: skip
    return "_".join(sorted(map(str, names))) or None


#: modules holding the suite's longest tests (paper figures, the wheel, full engagements,
#: corner schedules: 10-50 s each on a 2-core host), collected first: pytest-xdist hands
#: the tests out in collection order, so a long test collected last kept one worker busy
#: after the other had finished (order within a module, and module fixtures, unchanged)
LONG_FIRST = (
    "test_pictures.py", "test_wheel.py", "test_nodeset_invariants.py",
    "test_soundness_physical.py", "test_intercept.py", "test_infoset.py",
)  # fmt: skip


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """``--dist loadgroup`` sends the tests of one ``xdist_group`` to one worker by the
    suffix ``@<group>`` that pytest-xdist appends to their node ids in each worker.
    pytest-xdist 3.8 writes it into ``item._nodeid``, which pytest 9 no longer reads
    (the id lives in ``item._id``): every group was silently split across the workers
    (two Dask clusters, the kp_fig5 corner schedule run twice). Where the suffix is
    missing, it is added here; a pytest where neither works stops the session.

    First, the modules of ``LONG_FIRST`` move to the front (a stable sort: the same order
    in every xdist worker, as pytest-xdist requires)."""
    rank = {name: i for i, name in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
    if not getattr(config.option, "loadgroup", False):  # set in an xdist worker
        return
    for item in items:
        group = _xdist_group(item)
        if group is None or item.nodeid.endswith(f"@{group}"):
            continue
        if not hasattr(item, "_id"):
            raise pytest.UsageError(f"cannot mark {item.nodeid} as xdist group {group!r}")
        from _pytest.nodeid import NodeId

        item._id = NodeId.parse(f"{item.nodeid}@{group}")


def pytest_sessionstart(session):
    """Under ``pytest -n``, compile the kernels into numba's on-disk cache once, before
    the workers start (:mod:`compile_kernels`; ``make test`` has already done it while
    mypy ran, and then this only loads them)."""
    config = session.config
    if hasattr(config, "workerinput") or not config.getoption("numprocesses", None):
        return  # an xdist worker (the controller did it), or one process (compiles on use)
    compile_kernels()


#: node ids of the collected tests that use ``dask_cluster`` and have not finished here
_DASK_USERS: set[str] = set()
#: the open cluster, closed after the last of ``_DASK_USERS`` (or at the session's end)
_DASK_OPEN: list = []


def pytest_collection_finish(session):
    _DASK_USERS.update(i.nodeid for i in session.items if "dask_cluster" in i.fixturenames)


def pytest_runtest_logfinish(nodeid, location):
    """An idle LocalCluster costs about 0.16 CPU-s per second (heartbeats of its
    scheduler and two workers): close it once every test using it has run in this
    process. (A user on another xdist worker keeps it open until the session's end.)"""
    _DASK_USERS.discard(nodeid)
    if _DASK_OPEN and not _DASK_USERS:
        _DASK_OPEN.pop().close()


@pytest.fixture(scope="session")
def dask_cluster():
    """One Dask LocalCluster (two single-threaded worker processes) for the session:
    starting one costs seconds of CPU, and the tests only need a scheduler whose workers
    run this package. Tests using it carry ``xdist_group("dask")`` so that under
    ``pytest -n`` one worker starts it (and closes it after the last of them)."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    )
    _DASK_OPEN.append(cluster)
    yield cluster
    if _DASK_OPEN:
        _DASK_OPEN.pop().close()


# scenario files of the command tests (a short engagement, a tiny reaction-wheel turn)
@pytest.fixture
def short(tmp_path) -> Path:
    p = tmp_path / "short.toml"
    p.write_text(SHORT)
    return p


@pytest.fixture
def tiny_rw(tmp_path) -> Path:
    p = tmp_path / "tiny_rw.toml"
    p.write_text(TINY_RW)
    return p
