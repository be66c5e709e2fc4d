"""The exceptions the command line turns into an exit status with one line.

:class:`InputError`: bad input, exit status 2. :class:`Terminated`: SIGTERM, taken like
Ctrl-C (finished runs saved, exit status 143). The signal handlers
(:mod:`.signals`) raise it where the signal lands; as library code may swallow an
exception raised there, the request is also kept (:func:`request_stop`) and checked
between runs (:func:`check_stop`).

Where this process waits on worker processes it holds the futures' locks, which an
exception raised by a signal handler would leave held (the pool's manager thread then
blocks on them and the interpreter cannot exit). There the handlers only record the
stop (:func:`stops_deferred`), and the waiting loop raises it within its poll period.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

T = TypeVar("T")


def runs_text(n: int) -> str:
    """``"1 run"``, ``"2 runs"``: a count of runs as the messages print it."""
    return f"{n} run" if n == 1 else f"{n} runs"


def stat_text(value: float | None, fmt: str) -> str:
    """A statistic as the summaries print it: ``-`` when no run gave one (``None`` after
    JSON, NaN before), else formatted (``inf`` for a run that never settled)."""
    return "-" if value is None or value != value else format(value, fmt)


def stats_text(stats: dict[str, float | None], fmt: str, keys) -> str:
    """The statistics ``keys`` of ``stats`` as a table cell, ``mean / p50 / ...``
    (:func:`stat_text` each)."""
    return " / ".join(stat_text(stats[k], fmt) for k in keys)


class InputError(Exception):
    """Bad user input: a missing file, bad TOML, an unknown key, a value out of range.

    The message is one line naming the file, the field and what is allowed.
    """


def built_or_refused(what: str, build: Callable[..., T], *args: Any) -> T:
    """``build(*args)``, or :class:`InputError` of one line, ``what`` and the error's first
    line: a plug-in built up front, whose error would otherwise fail every run."""
    try:
        return build(*args)
    except Exception as exc:
        raise InputError(f"{what}: {type(exc).__name__}: {exc}".splitlines()[0]) from None


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, SLURM, ``docker stop``), taken like Ctrl-C."""


_LOCK = threading.Lock()
_STOP: list[type[KeyboardInterrupt]] = []
_DEFERRED = [0]  # depth of nested stops_deferred() blocks


@contextmanager
def stops_deferred() -> Iterator[None]:
    """Within the block the signal handlers record a stop without raising it (see
    :func:`raises_now`); the caller checks :func:`check_stop` after the block."""
    _DEFERRED[0] += 1
    try:
        yield
    finally:
        _DEFERRED[0] -= 1


def raises_now() -> bool:
    """Whether a signal handler may raise its exception where the signal lands."""
    return _DEFERRED[0] == 0


def request_stop(kind: type[KeyboardInterrupt] = Terminated) -> None:
    """Record that the command must stop (the SIGTERM and SIGINT handlers)."""
    with _LOCK:
        _STOP[:] = [kind]


def clear_stop() -> None:
    with _LOCK:
        _STOP.clear()


def stop_requested() -> bool:
    """Whether a stop was requested (and not cleared)."""
    return bool(_STOP)


def check_stop() -> None:
    """Raise the requested stop (:class:`Terminated`, ``KeyboardInterrupt``), if any."""
    if _STOP:
        raise _STOP[0]


def causes(exc: BaseException) -> Iterator[BaseException]:
    """``exc`` and the exceptions behind it (``__cause__``, else ``__context__``)."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        yield cur
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__


def reraise_stop(exc: BaseException) -> None:
    """Raise the stop (``KeyboardInterrupt``, :class:`Terminated`) behind ``exc``, if
    there is one: C code that a signal interrupts (numba's dispatcher, an extension's
    import) returns it as another error, caused by it (``SystemError: ... returned a
    result with an exception set``, ``ImportError: initialization failed``)."""
    for cur in causes(exc):
        if isinstance(cur, KeyboardInterrupt):
            raise cur
