"""The compiled kernels' cache: a user folder when the sources are read-only, and a
notice on stderr when numba compiles (a first run), silent when it loads the cache."""

import os
import subprocess
import sys
from pathlib import Path

from kalman_vs_infoset import _numba_cache as nc

#: a tiny kernel module (compiles in a fraction of a second), imported in a subprocess
#: after the cache is configured for a read-only source folder
_TINY = """
from numba import njit

@njit(cache=True)
def add_one(x):
    return x + 1.0
"""

_RUN = """
import sys
from pathlib import Path
from pathlib import Path
from kalman_vs_infoset import _numba_cache as nc
print("dir", nc.configure(source_dir=Path(sys.argv[1])))
notice = nc.CompileNotice("tiny").install()
sys.path.insert(0, sys.argv[2])
import tiny_kernel
assert tiny_kernel.add_one(1.0) == 2.0
notice.report()
"""


def test_user_cache_folder_follows_xdg_cache_home(tmp_path):
    assert nc.user_cache_dir({"XDG_CACHE_HOME": str(tmp_path)}) == (
        tmp_path / "kalman_vs_infoset" / "numba"
    )
    assert nc.user_cache_dir({"XDG_CACHE_HOME": ""}).parts[-3:] == (
        ".cache",
        "kalman_vs_infoset",
        "numba",
    )


def test_a_folder_numba_cannot_write_into_is_detected(tmp_path):
    assert nc.writable(tmp_path)
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert not nc.writable(blocker / "package")  # its parent is a file: even root fails


def test_read_only_sources_compile_once_into_the_user_cache_and_say_so(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    (src / "tiny_kernel.py").write_text(_TINY)
    blocker = tmp_path / "read_only"
    blocker.write_text("")
    env = {k: v for k, v in os.environ.items() if k != nc.ENV}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    cache = tmp_path / "cache" / "kalman_vs_infoset" / "numba"

    def run():
        return subprocess.run(
            [sys.executable, "-c", _RUN, str(blocker / "pkg"), str(src)],
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
            check=True,
        )

    first = run()
    assert f"dir {cache}" in first.stdout
    lines = first.stderr.strip().splitlines()
    assert len(lines) == 2, first.stderr
    assert lines[0].startswith("tiny: compiling numba kernels") and str(cache) in lines[0]
    assert lines[1].startswith("tiny: compiled the numba kernels in ") and "CPU-s" in lines[1]
    assert list(cache.rglob("*.nbi")), "no index in the user cache"
    second = run()  # loaded from the cache: nothing compiled, nothing said
    assert second.stderr == ""


def test_a_user_numba_cache_dir_is_kept(monkeypatch, tmp_path):
    monkeypatch.setenv(nc.ENV, str(tmp_path))
    assert nc.configure(source_dir=tmp_path / "nowhere" / "x") is None
    assert os.environ[nc.ENV] == str(tmp_path)


# Two kernel modules, the caller's kernel inlining the helper's (as ``apply_ops`` calls
# ``estim.common._kernels``); the caller's file never changes below.
_HELPER = """
from pathlib import Path
from kalman_vs_infoset import _jit
assert _jit.install((Path(__file__).resolve().parent,))
from numba import njit

@njit(cache=True)
def scale(x):
    return {factor} * x
"""

_CALLER = """
from pathlib import Path
from kalman_vs_infoset import _jit
assert _jit.install((Path(__file__).resolve().parent,))
from numba import njit
from helper_kernel import scale

@njit(cache=True)
def twice_scaled(x):
    return 2.0 * scale(x)
"""

_CALL = """
import sys
from pathlib import Path
sys.path.insert(0, sys.argv[1])
import caller_kernel
print(caller_kernel.twice_scaled(1.0), sum(caller_kernel.twice_scaled.stats.cache_hits.values()))
"""


def test_an_edit_of_a_called_kernel_recompiles_its_callers_cached_code(tmp_path):
    """numba stamps a cached kernel with its own file only: with the package's locator
    (``kalman_vs_infoset._jit``) the stamp covers every kernel source, so an edit of
    the helper reaches the caller's cached code (numba alone kept ``2 * 3``)."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "caller_kernel.py").write_text(_CALLER)
    env = {k: v for k, v in os.environ.items() if k != nc.ENV}
    # without bytecode files: Python stamps a .pyc with the source's size and its mtime
    # in whole seconds, and the edit below keeps the size, so an edit within the second
    # loaded the old helper (1 run in 4 where bytecode is written, the default)
    env["PYTHONDONTWRITEBYTECODE"] = "1"

    def value(factor: float) -> tuple[float, int]:
        (src / "helper_kernel.py").write_text(_HELPER.format(factor=factor))
        out = subprocess.run([sys.executable, "-c", _CALL, str(src)], capture_output=True,
                             text=True, env=env, timeout=300, check=True)  # fmt: skip
        got, hits = out.stdout.split()
        return float(got), int(hits)

    assert value(3.0) == (6.0, 0)  # compiled
    assert value(3.0) == (6.0, 1)  # the same sources: loaded from the cache
    assert value(5.0) == (10.0, 0)  # the helper changed: the caller compiled again


def test_the_package_kernels_are_stamped_with_every_kernel_source():
    """Every module of the package with a kernel is under the locator's roots and
    compiles through its ``njit``; the locator is first in numba's list."""
    from numba.core import caching

    from kalman_vs_infoset import _jit

    root = Path(__file__).resolve().parents[1]
    marked = {p for d in ("estim", "guidance", "experiments", "kalman_vs_infoset", "data")
              for p in (root / d).rglob("*.py") if b"@njit" in p.read_bytes()}  # fmt: skip
    marked.discard(root / "kalman_vs_infoset" / "_jit.py")  # its own text names the mark
    assert marked and marked == set(_jit.kernel_files())
    for path in marked:
        text = path.read_text()
        assert "from numba import njit" not in text, path
        assert "from kalman_vs_infoset._jit import njit" in text, path
    assert _jit.install()
    assert caching.CompileResultCacheImpl._locator_classes[0].kvi_roots == _jit._roots()
