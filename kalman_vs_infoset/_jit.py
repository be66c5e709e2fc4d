"""``njit`` for the package's kernels: their on-disk cache is keyed on every kernel source.

numba checks a cached kernel against its own source file only. A kernel inlines the
kernels it calls from other modules (``apply_ops`` calls ``estim.common._kernels``), so
an edit there left the caller's cached machine code in use: the old code ran, silently,
until its own file changed too (measured: an edit of ``_dedupe_tail`` did not reach
``apply_ops`` from the cache). The package's kernels are therefore compiled through
:func:`njit` here, which registers a cache locator for the files of :data:`ROOTS`. It
finds the cache where numba would (numba's own locators, in their order) and stamps it
with numba's stamp of the file *and* a digest of every kernel source of the package
(each ``.py`` file under the roots that has ``@njit``): an edit of any kernel recompiles
every kernel once. Functions elsewhere (a user's own numba code) keep numba's locators.

The locator list is the class attribute ``_locator_classes`` of the cache that ``njit``
uses (``numba.core.caching.CompileResultCacheImpl``; not public API): :func:`install`
returns False where it is missing, and the tests (an edit of a called kernel must
recompile its caller) fail then.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: the subpackages whose modules hold the compiled kernels
ROOTS = ("kalman_vs_infoset.estim", "kalman_vs_infoset.guidance")

#: what marks a file as a kernel source
MARK = b"@njit"


@functools.cache
def _roots() -> tuple[Path, ...]:
    """The folders of :data:`ROOTS` as installed (editable or not)."""
    out: list[Path] = []
    for name in ROOTS:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.submodule_search_locations:
            out.extend(Path(p).resolve() for p in spec.submodule_search_locations)
    return tuple(out)


@functools.cache
def kernel_files(roots: tuple[Path, ...] | None = None) -> tuple[Path, ...]:
    """Every ``.py`` file under ``roots`` (default: the package's) with a kernel."""
    roots = _roots() if roots is None else roots
    return tuple(p for r in roots for p in sorted(r.rglob("*.py")) if MARK in p.read_bytes())


@functools.cache
def sources_digest(roots: tuple[Path, ...] | None = None) -> str:
    """sha256 over the kernel files' paths (relative to their root) and contents."""
    roots = _roots() if roots is None else roots
    h = hashlib.sha256()
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            data = path.read_bytes()  # read once: marked and hashed
            if MARK in data:
                h.update(path.relative_to(root).as_posix().encode() + b"\0" + data + b"\0")
    return h.hexdigest()


def _under(path: str, roots: tuple[Path, ...]) -> bool:
    try:
        p = Path(path).resolve()
    except OSError:
        return False
    return any(p.is_relative_to(r) for r in roots)


def install(roots: tuple[Path, ...] | None = None) -> bool:
    """Put the stamping locator first in numba's list (once per process and roots);
    False when this numba has no such list."""
    from numba.core import caching

    impl = getattr(caching, "CompileResultCacheImpl", None)
    classes = getattr(impl, "_locator_classes", None)
    if impl is None or not isinstance(classes, list):
        return False
    roots = _roots() if roots is None else roots
    if any(getattr(c, "kvi_roots", None) == roots for c in classes):
        return True
    numbas = [c for c in classes if getattr(c, "kvi_roots", None) is None]

    class KernelSourcesLocator(caching._CacheLocator):
        """numba's locator for the file, stamped with the kernel sources' digest."""

        kvi_roots = roots

        def __init__(self, inner: Any) -> None:
            self._inner = inner

        def __getattr__(self, name: str) -> Any:  # numba reads e.g. ``_py_file`` directly
            return getattr(self._inner, name)

        def ensure_cache_path(self) -> None:
            self._inner.ensure_cache_path()

        def get_cache_path(self) -> str:
            return self._inner.get_cache_path()

        def get_disambiguator(self) -> str:
            return self._inner.get_disambiguator()

        def get_source_stamp(self) -> Any:
            return (self._inner.get_source_stamp(), sources_digest(roots))

        @classmethod
        def from_function(cls, py_func, py_file):
            if not _under(py_file, roots):
                return None
            for other in numbas:
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    return cls(inner)
            return None

    classes.insert(0, KernelSourcesLocator)
    return True


def njit(*args: Any, **kwargs: Any) -> Callable[..., Any]:
    """``numba.njit`` with the package's cache locator installed first (same arguments)."""
    import numba

    install()
    return numba.njit(*args, **kwargs)
