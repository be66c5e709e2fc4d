"""Progress of long loops: a bar where one can be drawn, log lines where it cannot.

:func:`progress_bar` is a ``tqdm.auto`` bar (a terminal's text bar, or a notebook's
widget) when stderr is a terminal or the code runs in Jupyter; when stderr is a file or
a pipe (a batch job's log), the bar is not drawn and the ``kalman_vs_infoset`` logger
writes one INFO line every :data:`LOG_EVERY_S` seconds instead (and one at the end
when it wrote any: a short loop stays silent). A single run that takes long shows its
steps the same way (:func:`step_progress`, within :func:`steps_shown`).
:func:`configure_logging` (called by the command line) sends that logger's lines to
stderr; a library user configures :mod:`logging` as usual.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from tqdm.auto import tqdm

#: the package's logger (``logging.getLogger("kalman_vs_infoset")``)
LOG = logging.getLogger("kalman_vs_infoset")
#: seconds between two progress lines in a log
LOG_EVERY_S = 30.0


def _in_notebook() -> bool:
    shell = sys.modules.get("IPython")
    ip = getattr(shell, "get_ipython", lambda: None)() if shell else None
    return type(ip).__name__ == "ZMQInteractiveShell"


def _isatty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed stderr
        return False


class _LogProgress:
    """A bar's interface (``update``, ``close``) writing log lines instead."""

    def __init__(
        self, total: int, initial: int, desc: str, every_s: float, unit: str = "runs"
    ) -> None:
        self.total, self.n, self.desc, self.every_s = total, initial, desc, every_s
        self.unit = unit
        self.t0 = self.last = time.monotonic()
        self.start, self.lines = initial, 0

    def update(self, n: int = 1) -> None:
        self.n += n
        now = time.monotonic()
        if now - self.last >= self.every_s:
            self.last = now
            self.lines += 1
            self._line(now)

    def _line(self, now: float, done: str = "") -> None:
        rate = (self.n - self.start) / max(now - self.t0, 1e-9)
        left = (self.total - self.n) / rate if rate > 0 else float("inf")
        eta = f", ~{left:.0f} s left" if self.n < self.total and rate > 0 else ""
        LOG.info("%s: %d/%d %s%s%s", self.desc, self.n, self.total, self.unit, eta, done)

    def close(self) -> None:
        if self.lines:  # a closing line for a loop long enough to have logged
            self._line(time.monotonic(), f" ({time.monotonic() - self.t0:.1f} s)")


def progress_bar(
    total: int, initial: int, desc: str, enabled: bool = True, every_s: float | None = None
) -> Any:
    """A progress reporter with ``update(n)`` and ``close()``: a ``tqdm.auto`` bar on a
    terminal or in a notebook, periodic log lines otherwise, nothing when disabled."""
    if not enabled:
        return tqdm(total=total, initial=initial, disable=True)
    announce_compile()
    if _isatty() or _in_notebook():
        return tqdm(total=total, initial=initial, desc=desc, file=sys.stderr, leave=False)
    return _LogProgress(total, initial, desc, LOG_EVERY_S if every_s is None else every_s)


#: a single run shows its steps once it has taken this long (wall clock, s)
SLOW_RUN_S = 10.0
#: the process whose runs show their steps (:func:`steps_shown`), or None
_steps_pid: int | None = None


@contextmanager
def steps_shown(enabled: bool = True) -> Iterator[None]:
    """In the block, a slow run in this process shows its steps (:func:`step_progress`).
    Only this process: runs on pool workers are shown by the runs' bar alone."""
    global _steps_pid
    before = _steps_pid
    _steps_pid = os.getpid() if enabled else None
    try:
        yield
    finally:
        _steps_pid = before


class _SlowRun:
    """Silent for :data:`SLOW_RUN_S`, then a bar of the run's steps (terminal, notebook)
    or a log line every ``every_s``."""

    def __init__(
        self, total: int, desc: str, after_s: float, every_s: float, unit: str = "step"
    ) -> None:
        self.total, self.desc, self.after_s, self.every_s = total, desc, after_s, every_s
        self.unit = unit
        self.t0 = time.monotonic()
        self.bar: Any = None

    def __call__(self, done: int) -> None:
        if self.bar is None:
            if time.monotonic() - self.t0 < self.after_s:
                return
            if _isatty() or _in_notebook():
                self.bar = tqdm(total=self.total, initial=done, desc=self.desc, unit=self.unit,
                                file=sys.stderr, leave=False)  # fmt: skip
            else:
                self.bar = _LogProgress(
                    self.total, 0, self.desc, self.every_s, f"{self.unit}s (at most)"
                )
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@contextmanager
def step_progress(
    total: int,
    desc: str,
    after_s: float | None = None,
    every_s: float | None = None,
    unit: str = "step",
) -> Iterator[Callable[[int], None]]:
    """A callable ``shown(done)`` taking the steps done of one run: nothing for a run
    faster than ``after_s`` (default :data:`SLOW_RUN_S`) or outside :func:`steps_shown`,
    else a bar of the steps, or a log line every ``every_s`` (default
    :data:`LOG_EVERY_S`) where no bar can be drawn. ``total`` is the run's step bound;
    ``unit`` names what is counted (``"step"``; ``kvi attitude-tightness``: ``"program"``)."""
    if _steps_pid != os.getpid():
        yield lambda done: None
        return
    run = _SlowRun(
        total,
        desc,
        SLOW_RUN_S if after_s is None else after_s,
        LOG_EVERY_S if every_s is None else every_s,
        unit,
    )
    try:
        yield run
    finally:
        run.close()


class _Stderr(logging.Handler):
    """Writes to the current ``sys.stderr`` (which may be replaced after set-up)."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            sys.stderr.write(self.format(record) + "\n")
        except Exception:
            self.handleError(record)


def configure_logging(level: int = logging.INFO) -> None:
    """Send the package's log lines to stderr (``kvi: message``), once."""
    if not any(isinstance(h, _Stderr) for h in LOG.handlers):
        handler = _Stderr()
        handler.setFormatter(logging.Formatter("kvi: %(message)s"))
        LOG.addHandler(handler)
    LOG.setLevel(level)


def compiled_kernels_cached() -> bool | None:
    """Whether numba's on-disk cache holds the compiled kernels of every kernel source of
    the package, written after the last edit of any of them (the cache is stamped with
    all of them: :mod:`kalman_vs_infoset._jit`). ``None``: unknown (the sources' folder
    is not writable, so numba caches elsewhere, per user). A guess from the files, for
    the progress bars of library users; the command line sees each compilation."""
    import os

    from kalman_vs_infoset._jit import kernel_files

    files = kernel_files()
    if not files:
        return None
    folder = os.environ.get("NUMBA_CACHE_DIR")
    if not folder and not os.access(files[0].parent, os.W_OK):
        return None
    newest = max(p.stat().st_mtime for p in files)

    def cached(src: Path) -> bool:
        # numba names a kernel's index <module>.<function>-<line>.py<version>.nbi, in
        # __pycache__ beside its source, or under NUMBA_CACHE_DIR
        pattern = f"{src.stem}.*.nbi"
        where = Path(folder) if folder else src.parent / "__pycache__"
        found = where.rglob(pattern) if folder else where.glob(pattern)
        return any(f.stat().st_mtime >= newest for f in found)

    return all(cached(src) for src in files)


_announced = False


def announce_compile() -> None:
    """One line, once, when the runs will compile the kernels first (the first run after
    an install: about a minute; the compiled code is cached for the next runs)."""
    global _announced
    if not _announced and compiled_kernels_cached() is False:
        _announced = True
        LOG.warning("first run: compiling the estimators' kernels (about a minute, once)")
