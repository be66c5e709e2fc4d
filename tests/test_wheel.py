"""The package as a user installs it: a wheel built from these sources, installed (not
editable) into a fresh virtual environment, run from an empty folder.

The environment sees this project's environment's site-packages for the dependencies
(a ``.pth`` file, no network), but the package itself only from the wheel. Numba's
compiled kernels are the one thing carried over: the wheel installs the same source
files, so their on-disk cache (``__pycache__/*.nbi, *.nbc``) is copied beside them with
the sources' modification times, saving the ~45 CPU-s first-run compile (which this test
does not measure); without a cache here the commands compile, slower but the same.
"""

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# one xdist worker builds the wheel and its environment (module fixtures) for all
pytestmark = pytest.mark.xdist_group("wheel")
LAYERS = ("estim", "guidance", "experiments")
SOURCES = ("kalman_vs_infoset", "data", *LAYERS)
IGNORE = shutil.ignore_patterns(
    "__pycache__",
    "*.pyc",
    "*.tmp",
    "*.egg-info",
    "_build",
    "auto_examples",
    "generated",
    "sg_execution_times.rst",
)


def _copy_sources(dst: Path) -> Path:
    """What a build needs, copied from the working tree (so the build writes nothing
    into the repository)."""
    for name in ("pyproject.toml", "README.md", "LICENSE", "MANIFEST.in", "CHANGELOG.md",
                 "CITATION.cff", "Makefile"):  # fmt: skip
        shutil.copy2(ROOT / name, dst / name)
    for name in (*SOURCES, "docs", "tests"):
        shutil.copytree(ROOT / name, dst / name, ignore=IGNORE)
    return dst


def _run(args, cwd, env, timeout=600) -> subprocess.CompletedProcess:
    r = subprocess.run(
        [str(a) for a in args], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout
    )
    assert r.returncode == 0, f"{args}: {r.stderr[-2000:]}"
    return r


def _project_version() -> str:
    import tomllib

    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]


def _seed_numba_cache(installed: Path) -> None:
    for layer in LAYERS:
        for src in (ROOT / layer).rglob("*.py"):
            st = src.stat()
            os.utime(
                installed / layer / src.relative_to(ROOT / layer),
                ns=(st.st_atime_ns, st.st_mtime_ns),
            )
        for cached in (ROOT / layer).rglob("*.nb[ic]"):
            target = installed / layer / cached.relative_to(ROOT / layer)
            target.parent.mkdir(exist_ok=True)
            shutil.copy2(cached, target)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """``(wheel, sdist)`` built from a copy of the sources, without build isolation: the
    PEP 517 hooks of the project's backend called in one process (what ``pip wheel
    --no-deps --no-build-isolation`` calls, without pip's own start-up)."""
    src = _copy_sources(tmp_path_factory.mktemp("src"))
    dist = tmp_path_factory.mktemp("dist")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    build = (f"from setuptools import build_meta as b; d = {str(dist)!r}; "
             "print(b.build_wheel(d), b.build_sdist(d))")  # fmt: skip
    _run([sys.executable, "-c", build], src, env)
    (wheel,) = dist.glob("*.whl")
    (sdist,) = dist.glob("*.tar.gz")
    return wheel, sdist


@pytest.fixture(scope="module")
def venv(built, tmp_path_factory):
    """A fresh environment with the wheel installed; ``(bin folder, site-packages, env)``."""
    root = tmp_path_factory.mktemp("venv")
    # the environment sits inside a user's own git repository (with one commit)
    git = ["git", "-c", "user.name=u", "-c", "user.email=u@example.org"]
    _run([*git, "init", "-q", root], root, None)
    _run([*git, "commit", "-q", "--allow-empty", "-m", "user's work"], root, None)
    _run([sys.executable, "-m", "venv", "--without-pip", root / "venv"], root, None)
    root = root / "venv"
    python = root / "bin" / "python"
    site = Path(
        subprocess.check_output(
            [python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"], text=True
        ).strip()
    )
    (site / "_project_dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    # numba reads the cache seeded beside the installed sources only without a
    # NUMBA_CACHE_DIR (with one, every command here compiled: about 80 CPU-s)
    drop = ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR")
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["MPLBACKEND"] = "Agg"
    # first the index's own "guidance" (a language-model library): ours must sit beside it
    index = subprocess.run(
        [sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
         "guidance"], cwd=root, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    guidance_error = index.stderr.strip().splitlines()[-1:] if index.returncode else None
    _run([sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
          built[0]], root, env)  # fmt: skip
    _seed_numba_cache(site / "kalman_vs_infoset")
    return root / "bin", site, env, guidance_error


def test_the_wheel_installs_one_top_level_name_and_its_data(built):
    with zipfile.ZipFile(built[0]) as whl:
        names = whl.namelist()
        (record,) = [n for n in names if n.endswith(".dist-info/RECORD")]
        rows = whl.read(record).decode().splitlines()
    tops = {row.split(",")[0].split("/")[0] for row in rows}
    assert tops == {"kalman_vs_infoset", record.split("/")[0]}
    assert not {"estim", "guidance", "experiments", "data", "tests"} & tops
    data = {n.removeprefix("kalman_vs_infoset/data/") for n in names if "/data/" in n}
    bundled = [p for p in (ROOT / "data").rglob("*") if p.suffix in (".toml", ".csv", ".py")]
    expected = {p.relative_to(ROOT / "data").as_posix() for p in bundled}
    assert data == expected and "reference/f0_table.csv" in data
    assert "kalman_vs_infoset/py.typed" in names


def test_the_sdist_carries_what_its_tests_need(built):
    with tarfile.open(built[1]) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
    needed = ["data/scenarios/kp_fig3.toml", "data/reference/f0_table.csv", "docs/models.md"]
    needed += ["tests/conftest.py", "tests/harness_texts.py", "CHANGELOG.md", "CITATION.cff"]
    for name in [*needed, "README.md", "kalman_vs_infoset/py.typed"]:
        assert name in names, name
    tests = {p.name for p in (ROOT / "tests").glob("*.py")}
    assert tests <= {n.removeprefix("tests/") for n in names}


def test_the_commands_work_from_an_empty_folder(venv, tmp_path):
    """``kvi scenarios``, ``kvi intercept kp_fig3 --runs 2``, ``kvi pd-gains`` (quick
    settings, which reads the bundled f0 table) and ``kvi paper-figures --quick`` (two
    groups of bundled scenarios: kp_fig4, an intercept trace, and the gyrostat's attitude
    turns) from the installed wheel, in a folder with no data. (The groups kp_fig3 and
    "akimov" were drawn here before: about 18 CPU-s more, and no installed file that
    these do not read.)"""
    bin_dir, site, env, _ = venv
    kvi = bin_dir / "kvi"
    where = _run([bin_dir / "python", "-c", "import kalman_vs_infoset as k; print(k.__file__)"],
                 tmp_path, env).stdout  # fmt: skip
    assert Path(where.strip()).parent == site / "kalman_vs_infoset"
    listing = _run([kvi, "scenarios"], tmp_path, env).stdout.splitlines()
    assert [line.split()[0] for line in listing] == sorted(
        p.stem for p in (ROOT / "data" / "scenarios").glob("*.toml")
    )
    out = _run([kvi, "intercept", "kp_fig3", "--runs", "2", "--json", "--no-progress"],
               tmp_path, env).stdout  # fmt: skip
    result = json.loads(out.strip().splitlines()[-1])
    assert result["runs"] == 2 and result["failures"] == 0
    assert (tmp_path / result["out"]).is_dir()
    meta = (
        "import json, sys, kalman_vs_infoset as k; print(json.dumps(k.read_metadata(sys.argv[1])))"
    )
    table = tmp_path / result["out"] / "kp_fig3-infoset-random-s3.parquet"
    code = json.loads(_run([bin_dir / "python", "-c", meta, table], tmp_path, env).stdout)["code"]
    assert code["version"] == _project_version()
    assert code["git_commit"] is None  # the package's own commit is unknown, not the user's
    out = _run([kvi, "pd-gains", "--angles-deg", "1.0,5.0", "--grid-step", "0.2", "--json"],
               tmp_path, env).stdout  # fmt: skip
    gains = json.loads(out.strip().splitlines()[-1])
    # the seed's f0 values as the installed wheel read them from its bundled table
    rows = (ROOT / "data" / "reference" / "f0_table.csv").read_text().splitlines()
    table = dict(r.split(",")[:2] for r in rows if r[:1].isdigit())
    assert gains["seed_table"] == {a: float(table[a]) for a in ("1.0", "5.0")}
    assert list((tmp_path / "results" / "pd_gains").glob("*.png"))
    _run([kvi, "paper-figures", "--quick", "--runs", "2", "--only", "kp_fig4,gyrostat"],
         tmp_path, env)  # fmt: skip
    written = json.loads((tmp_path / "results" / "figures" / "paper_figures.json").read_text())
    assert written["quick"] is True and written["numbers"]
    figures = {p.stem for p in (tmp_path / "results" / "figures").glob("*.png")}
    assert {"kp_fig4", "gyrostat_eta", "gyrostat_switching", "gyrostat_torques"} <= figures


def _files(bin_dir: Path, env, *dists: str) -> list[tuple[Path, set[str]]]:
    """Each distribution's location and its files (relative paths), as ``pip show -f``
    lists them (its RECORD, through the environment's own ``importlib.metadata``; one
    interpreter for all, instead of one pip start-up each)."""
    code = (
        "import importlib.metadata as m, json, sys; print(json.dumps([[str(d.locate_file('')), "
        "[str(f) for f in d.files]] for d in map(m.distribution, sys.argv[1:])]))"
    )
    out = json.loads(_run([bin_dir / "python", "-c", code, *dists], bin_dir, env).stdout)
    return [(Path(loc), {f for f in files if not f.startswith("..")}) for loc, files in out]


def test_the_wheel_sits_beside_the_index_guidance_package(venv, tmp_path):
    """The index's ``guidance`` installed first, then the wheel: the two file lists are
    disjoint and none of guidance's files changed (its RECORD hashes); our guidance layer
    imports, and ``kvi --help`` works in a folder holding an ``experiments/`` package."""
    import base64
    import hashlib

    bin_dir, site, env, guidance_error = venv
    if guidance_error is not None:
        pytest.skip(f"the index's 'guidance' could not be installed: {guidance_error}")
    (where, theirs), (_, ours) = _files(bin_dir, env, "guidance", "kalman-vs-infoset")
    assert "guidance/__init__.py" in theirs and "kalman_vs_infoset/guidance/__init__.py" in ours
    assert not theirs & ours
    (record,) = where.glob("guidance-*.dist-info/RECORD")
    for row in record.read_text().splitlines():
        path, digest, _ = row.rsplit(",", 2)
        if digest.startswith("sha256="):
            raw = hashlib.sha256((where / path).read_bytes()).digest()
            assert base64.urlsafe_b64encode(raw).rstrip(b"=").decode() == digest[7:], path
    project = tmp_path / "project"
    (project / "experiments").mkdir(parents=True)
    (project / "experiments" / "__init__.py").write_text("raise ImportError('not ours')\n")
    probe = "import kalman_vs_infoset.guidance.intercept.law as g; print(g.__file__)"
    where_ours = _run([bin_dir / "python", "-c", probe], project, env).stdout.strip()
    assert Path(where_ours).is_relative_to(site / "kalman_vs_infoset" / "guidance")
    for cmd in ([bin_dir / "kvi", "--help"], [bin_dir / "python", "-m", "kalman_vs_infoset", "-h"]):
        assert "intercept" in _run(cmd, project, env).stdout
