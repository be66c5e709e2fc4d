"""Where numba keeps the compiled kernels, and a notice when it compiles them.

The kernels are compiled with ``cache=True``: once per install, then loaded from disk
(about 40 CPU-s of compilation on a first run, well under a second to load). numba
writes its cache beside the sources (``__pycache__``) by default; when that folder is
not writable (a package installed read-only, system-wide or in a container image),
:func:`configure` points numba at a user cache folder instead, before numba is
imported: ``$XDG_CACHE_HOME/kalman_vs_infoset/numba`` (``~/.cache/...`` when
``XDG_CACHE_HOME`` is unset). A ``NUMBA_CACHE_DIR`` set by the user is kept.

:class:`CompileNotice` tells the user, on stderr, when the kernels are being compiled
(a kernel missing from the cache) and how long it took.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TextIO

#: the environment variable numba reads at import
ENV = "NUMBA_CACHE_DIR"


def user_cache_dir(environ: Mapping[str, str] | None = None) -> Path:
    """``$XDG_CACHE_HOME/kalman_vs_infoset/numba`` (``~/.cache`` when unset or empty)."""
    env = os.environ if environ is None else environ
    root = env.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "kalman_vs_infoset" / "numba"


def writable(folder: Path) -> bool:
    """Whether numba can write its cache beside sources in ``folder``: it creates
    ``folder/__pycache__`` and writes there (tried, not asked: ``os.access`` says yes to
    root on a read-only mount)."""
    cache = folder / "__pycache__"
    try:
        cache.mkdir(exist_ok=True)
        with tempfile.TemporaryFile(dir=cache):
            pass
    except OSError:
        return False
    return True


def _kernel_sources() -> Path:
    """The folder of the compiled kernels' sources (the ``estim`` layer)."""
    try:
        spec = importlib.util.find_spec("kalman_vs_infoset.estim")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations)))
    return Path(__file__).resolve().parent


def configure(source_dir: Path | None = None) -> Path | None:
    """Point numba at the user cache folder when the kernels' source folder is not
    writable; return the folder set (None: numba's default or the user's own
    ``NUMBA_CACHE_DIR`` is kept). Call before numba is imported; if it already is,
    its configuration is updated too."""
    if os.environ.get(ENV):
        return None
    if writable(source_dir if source_dir is not None else _kernel_sources()):
        return None
    folder = user_cache_dir()
    os.environ[ENV] = str(folder)
    config = sys.modules.get("numba.core.config")
    if config is not None:
        setattr(config, "CACHE_DIR", str(folder))  # noqa: B010 - a module's attribute, set at run time
    return folder


def cache_location() -> str:
    """Where the cache is, in words, for messages."""
    return os.environ.get(ENV) or "__pycache__ beside the sources"


class CompileNotice:
    """Says on ``stream`` when numba starts compiling (a kernel missing from the cache),
    in one line, and, through :meth:`report`, how long the compilation took in CPU time.

    Listens to numba's ``numba:compile`` event, which fires only when a kernel is
    compiled, not when it is loaded from the cache. Only the process that installed
    it speaks (forked workers inherit the listener and stay silent)."""

    def __init__(self, prog: str = "kvi", stream: TextIO | None = None) -> None:
        self.prog, self.stream = prog, stream
        self.pid = os.getpid()
        self.depth, self.kernels = 0, 0
        self.cpu_s, self._t0 = 0.0, 0.0
        self._listener: Any = None  # numba's event listener while installed
        self.aside_kernels, self.aside_cpu_s = 0, 0.0  # a helper process's compilations

    def install(self) -> CompileNotice:
        from numba.core import event

        notice = self

        class _Listener(event.Listener):
            def on_start(self, ev):
                notice._start()

            def on_end(self, ev):
                notice._end()

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        _INSTALLED.append(self)
        return self

    def uninstall(self) -> None:
        if self._listener is not None:
            from numba.core import event

            event.unregister("numba:compile", self._listener)
            self._listener = None
            if self in _INSTALLED:
                _INSTALLED.remove(self)

    def _out(self) -> TextIO:
        return self.stream if self.stream is not None else sys.stderr

    def _start(self) -> None:
        if os.getpid() != self.pid:
            return
        self.depth += 1
        if self.depth > 1:
            return
        if self.kernels == 0:
            print(
                f"{self.prog}: compiling numba kernels (not in the cache yet: "
                f"{cache_location()}; once per install) ...",
                file=self._out(),
                flush=True,
            )
        self.kernels += 1
        self._t0 = time.process_time()

    def _end(self) -> None:
        if os.getpid() != self.pid:
            return
        self.depth -= 1
        if self.depth == 0:
            self.cpu_s += time.process_time() - self._t0

    def report(self) -> None:
        """One line with the compilation's CPU time, if anything was compiled."""
        if (self.kernels or self.aside_kernels) and os.getpid() == self.pid:
            cpu_s = self.cpu_s + self.aside_cpu_s
            n = self.aside_kernels
            aside = f", {n} of them in a helper process" if n else ""
            print(
                f"{self.prog}: compiled the numba kernels in {cpu_s:.1f} CPU-s "
                f"({self.kernels + self.aside_kernels} compilations{aside}; cached: later "
                "runs load them)",
                file=self._out(),
                flush=True,
            )


#: the notices installed in this process (the helper's compilations are added to them)
_INSTALLED: list[CompileNotice] = []


def note_compiled_aside(kernels: int, cpu_s: float) -> None:
    """Count ``kernels`` compilations of ``cpu_s`` CPU seconds that a helper process
    did for this one (:mod:`kalman_vs_infoset.experiments.warm`) in the notices
    installed here (their report adds them; the start line is this process's own, at
    its first compilation)."""
    for notice in _INSTALLED:
        if os.getpid() == notice.pid:
            notice.aside_kernels += kernels
            notice.aside_cpu_s += cpu_s
