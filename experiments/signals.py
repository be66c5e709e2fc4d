"""Ctrl-C and SIGTERM while a command runs: the handlers, and where they must not raise.

A handler records the stop (:func:`~.errors.request_stop`, checked between runs) and
raises it where the signal lands, so that a long run in this process stops at once.
Some places cannot take an exception, and there the stop is raised a moment later
instead (a timer, :data:`REDELIVER_S`):

* a module being imported: an extension module's initialisation turns it into
  ``ImportError: initialization failed``, and code that the interpreter runs from C
  (``PyRun_String``) marks it unhandled, so that the process ends by SIGINT (status
  -2) whatever the command returns;
* numba's and llvmlite's own Python code (loading or compiling a kernel): an object
  cut half-built there crashed the process when freed (a segmentation fault, seen
  once in 60 stops during the kernels' warm-up); the kernels' compiled code itself
  runs no Python, and a stop lands in the caller once it returns;
* a finalizer (``__del__``), where Python prints the exception as "Exception ignored
  in" and goes on (:func:`_on_unraisable`);
* a wait on the worker pool, which holds the futures' locks
  (:func:`~.errors.stops_deferred`; the waiting loop raises the stop itself).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from kalman_vs_infoset.experiments.errors import (
    Terminated,
    check_stop,
    raises_now,
    request_stop,
    stop_requested,
)

#: how soon a stop held back (an import, numba, a finalizer) is raised again (s)
REDELIVER_S = 0.01


#: the packages whose code holds a stop back (when imported)
HELD_PACKAGES = ("numba", "llvmlite")


def _held_back(frame) -> bool:
    """Whether ``frame`` runs inside an import or inside numba's or llvmlite's code
    (a frame of importlib or of their packages is on its stack)."""
    held = ["<frozen importlib"]
    for name in HELD_PACKAGES:
        package = sys.modules.get(name)
        held += [os.path.join(d, "") for d in getattr(package, "__path__", ())]
    starts = tuple(held)
    while frame is not None:
        if frame.f_code.co_filename.startswith(starts):
            return True
        frame = frame.f_back
    return False


def _later() -> None:
    """Raise the stop again in :data:`REDELIVER_S` (where there is no such timer, as on
    Windows, it comes at the next check between runs)."""
    if _TIMER:
        signal.setitimer(signal.ITIMER_REAL, REDELIVER_S)


_TIMER = hasattr(signal, "setitimer") and hasattr(signal, "SIGALRM")


def _raise_here(frame) -> bool:
    """Whether the stop may be raised where the signal landed; otherwise it is raised
    again :data:`REDELIVER_S` later (or by the waiting loop that defers it)."""
    if not raises_now():
        return False
    if _held_back(frame):
        _later()
        return False
    return True


def _on_sigterm(signum, frame) -> None:
    """SIGTERM, taken like Ctrl-C: what finished is saved and the command says so."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second one must not cut the save
    request_stop()  # checked between runs, should the exception below be swallowed
    if _raise_here(frame):
        raise Terminated


def _on_sigint(signum, frame) -> None:
    """Ctrl-C: ``KeyboardInterrupt``, also checked between runs."""
    request_stop(KeyboardInterrupt)
    if _raise_here(frame):
        raise KeyboardInterrupt


def _on_sigalrm(signum, frame) -> None:
    """A stop held back (an import, a finalizer), raised now if it may be."""
    if _raise_here(frame):
        check_stop()


def _on_unraisable(unraisable) -> None:
    """A stop raised inside a finalizer (numba's compiled objects have some): not
    printed, and raised again a moment later, outside it. Anything else goes to the
    hook that was there."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt) and stop_requested():
        _later()
        return
    _UNRAISABLE[0](unraisable)


_UNRAISABLE = [sys.__unraisablehook__]


@contextmanager
def handled() -> Iterator[None]:
    """The handlers of a command, in the main thread (elsewhere nothing changes), and
    the ones that were there put back after it. Ctrl-C is handled only where it is not
    ignored (a background job ignores it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    term = signal.signal(signal.SIGTERM, _on_sigterm)
    interactive = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if interactive:
        signal.signal(signal.SIGINT, _on_sigint)
    alarm = signal.signal(signal.SIGALRM, _on_sigalrm) if _TIMER else None
    _UNRAISABLE[0], sys.unraisablehook = sys.unraisablehook, _on_unraisable
    try:
        yield
    finally:
        if _TIMER:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, alarm)
        sys.unraisablehook = _UNRAISABLE[0]
        signal.signal(signal.SIGTERM, term)
        if interactive:
            signal.signal(signal.SIGINT, signal.default_int_handler)
