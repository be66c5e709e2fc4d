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


@pytest.fixture(scope="session")
def dask_cluster():
    """One Dask LocalCluster (two single-threaded worker processes) for the session:
    starting one costs seconds of CPU, and the tests only need a scheduler whose workers
    run this package. Tests using it carry ``xdist_group("dask")`` so that under
    ``pytest -n`` one worker starts it."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        yield cluster


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
