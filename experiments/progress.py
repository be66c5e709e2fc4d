"""Progress of long loops: a bar where one can be drawn, log lines where it cannot.

:func:`progress_bar` is a ``tqdm.auto`` bar (a terminal's text bar, or a notebook's
widget) when stderr is a terminal or the code runs in Jupyter; when stderr is a file or
a pipe (a batch job's log), the bar is not drawn and the ``kalman_vs_infoset`` logger
writes one INFO line every :data:`LOG_EVERY_S` seconds instead (and one at the end
when it wrote any: a short loop stays silent).
:func:`configure_logging` (called by the command line) sends that logger's lines to
stderr; a library user configures :mod:`logging` as usual.
"""

from __future__ import annotations

import logging
import sys
import time
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

    def __init__(self, total: int, initial: int, desc: str, every_s: float) -> None:
        self.total, self.n, self.desc, self.every_s = total, initial, desc, every_s
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
        LOG.info("%s: %d/%d runs%s%s", self.desc, self.n, self.total, eta, done)

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
    """Whether numba's on-disk cache holds the estimators' compiled kernels (``None``:
    unknown, the cache is not beside the sources)."""
    import os

    from kalman_vs_infoset import estim

    folder = os.environ.get("NUMBA_CACHE_DIR")
    if folder:
        return any(Path(folder).rglob("_kernels.*.nbi"))
    here = Path(estim.__file__).parent
    if not os.access(here, os.W_OK):  # numba caches elsewhere (per user)
        return None
    return any((here / "__pycache__").glob("_kernels.*.nbi"))


_announced = False


def announce_compile() -> None:
    """One line, once, when the runs will compile the kernels first (the first run after
    an install: about a minute; the compiled code is cached for the next runs)."""
    global _announced
    if not _announced and compiled_kernels_cached() is False:
        _announced = True
        LOG.warning("first run: compiling the estimators' kernels (about a minute, once)")
