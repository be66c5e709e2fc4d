"""The exceptions the command line turns into an exit status with one line.

:class:`InputError`: bad input, exit status 2. :class:`Terminated`: SIGTERM, taken like
Ctrl-C (finished runs saved, exit status 143). The signal handler raises it where the
signal lands; as library code may swallow an exception raised there, the request is
also kept (:func:`request_stop`) and checked between runs (:func:`check_stop`).
"""

from __future__ import annotations

import threading


class InputError(Exception):
    """Bad user input: a missing file, bad TOML, an unknown key, a value out of range.

    The message is one line naming the file, the field and what is allowed.
    """


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, SLURM, ``docker stop``), taken like Ctrl-C."""


_LOCK = threading.Lock()
_STOP: list[type[KeyboardInterrupt]] = []


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
