"""Where a signal lands: Ctrl-C and SIGTERM stop a command with one line and their exit
status wherever they arrive (while the command's module loads, inside a wait on the
worker pool, inside a finalizer), and leave nothing held.

In process, with the handlers called where the signal would land; the commands stopped
as real processes are in ``test_reliability_runs.py``, and ``stress_interrupts.py``
stops them at random moments by hand.
"""

from __future__ import annotations

import signal
import sys
import threading
import time
import types
from pathlib import Path

import pytest
from kalman_vs_infoset.experiments import cli, errors, executors, signals


@pytest.fixture
def handlers_kept():
    """Whatever a test's handler calls changes (SIGTERM ignored after a first one, a
    recorded stop) is put back."""
    before = signal.getsignal(signal.SIGTERM)
    errors.clear_stop()
    yield
    errors.clear_stop()
    signal.signal(signal.SIGTERM, before)


def _command_fake(monkeypatch, run) -> None:
    """``kvi fake``: a command module whose ``run`` is ``run``."""
    fake = types.ModuleType("fake_command")
    fake.add_arguments = lambda parser: None
    fake.run = run
    monkeypatch.setitem(sys.modules, "fake_command", fake)
    monkeypatch.setitem(cli.COMMANDS, "fake", ("fake_command", "a test's command"))


@pytest.mark.parametrize(("stop", "status", "line"), [
    (KeyboardInterrupt, 130, "kvi: interrupted"),
    (errors.Terminated, 143, "kvi: terminated (SIGTERM)"),
])  # fmt: skip
def test_a_stop_while_the_command_loads_is_one_line_and_its_status(
    stop, status, line, monkeypatch, capsys
):
    """A stop that escapes while the command's module loads (its imports: numpy,
    pandas, the kernels, up to a second) used to print Python's traceback: one line
    and the stop's status instead."""
    real = cli.importlib.import_module

    def import_module(name, *args):
        if name == cli.COMMANDS["scenarios"][0]:
            raise stop
        return real(name, *args)

    monkeypatch.setattr(cli.importlib, "import_module", import_module)
    try:
        got = cli.main(["scenarios"])
    except KeyboardInterrupt as exc:  # not re-raised: pytest would stop the session
        pytest.fail(f"{type(exc).__name__} escaped main() (a traceback for the user)")
    assert got == status
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [line], err


class _StopImporting:
    """A finder that stops the import of one module as a Ctrl-C would."""

    def __init__(self, name: str):
        self.name = name

    def find_spec(self, name, path=None, target=None):
        if name == self.name:
            raise KeyboardInterrupt
        return None


def test_a_ctrl_c_while_the_command_line_loads_is_one_line_and_130(monkeypatch, capsys):
    """The ``kvi`` script (and ``python -m kalman_vs_infoset``) imports the command line
    inside its own handler: a Ctrl-C landing there (before ``cli.main`` puts its
    handlers in place) printed Python's traceback, now one line and status 130; and
    the installed script is that entry point."""
    from importlib.metadata import entry_points

    from kalman_vs_infoset import _entry

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "kvi"]
    assert script.value == "kalman_vs_infoset._entry:main"
    main_py = (Path(_entry.__file__).parent / "__main__.py").read_text()
    assert "from kalman_vs_infoset._entry import main" in main_py
    monkeypatch.delitem(sys.modules, "kalman_vs_infoset.experiments.cli")
    monkeypatch.setattr(sys, "meta_path", [_StopImporting("kalman_vs_infoset.experiments.cli"),
                                           *sys.meta_path])  # fmt: skip
    try:
        got = _entry.main()
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped the entry point (a traceback for the user)")
    assert got == 130
    assert capsys.readouterr().err.strip().splitlines() == ["kvi: interrupted"]
    monkeypatch.undo()  # the command line loads again and runs
    monkeypatch.setattr(sys, "argv", ["kvi", "scenarios"])
    assert _entry.main() == 0
    assert "kp_fig3" in capsys.readouterr().out


def test_a_stop_landing_in_a_finalizer_is_not_printed_and_still_stops_the_command(
    monkeypatch, capsys, handlers_kept
):
    """A signal handled inside a ``__del__`` (numba's compiled objects have them, and the
    warm-up frees many): Python only prints the handler's exception ("Exception
    ignored in") and goes on. The command prints nothing of it and stops a moment
    later, outside the finalizer."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are installed in the main thread only")

    class Finalized:
        def __del__(self):
            signals._on_sigint(signal.SIGINT, None)  # Ctrl-C, landing here

    def run(args):
        Finalized()  # freed at once: the handler runs in its finalizer
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:  # a run with no check between runs
            sum(range(1000))
        return {"finished": True}

    _command_fake(monkeypatch, run)
    t0 = time.monotonic()
    status = cli.main(["fake"])
    took_s = time.monotonic() - t0
    err = capsys.readouterr().err
    assert status == 130 and took_s < 2.5, (status, took_s, err)
    assert "Exception ignored" not in err and "Traceback" not in err, err
    assert err.strip().splitlines()[-1].startswith("kvi fake: interrupted"), err
    assert sys.unraisablehook is not signals._on_unraisable  # put back


def test_a_stop_landing_in_an_import_is_raised_after_it(tmp_path, monkeypatch, handlers_kept):
    """An extension module whose initialisation a ``KeyboardInterrupt`` interrupts
    fails with ``ImportError: initialization failed`` (seen on Ctrl-C while scipy
    loaded), and code run from C marks it unhandled (the process then ended by SIGINT,
    status -2, after printing that it was interrupted). Landing in an import, the stop
    is held back: the module loads whole, and the stop comes right after."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are installed in the main thread only")
    (tmp_path / "slow_module.py").write_text(
        "import sys\n"
        "from kalman_vs_infoset.experiments import signals\n"
        "signals._on_sigint(2, sys._getframe())  # Ctrl-C while this module loads\n"
        "LOADED = True\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "slow_module", raising=False)
    deadline = time.monotonic() + 2.0
    with signals.handled(), pytest.raises(KeyboardInterrupt):
        __import__("slow_module")
        while time.monotonic() < deadline:  # the stop, raised again outside the import
            sum(range(1000))
    assert getattr(sys.modules.get("slow_module"), "LOADED", False), "the import was cut"
    assert time.monotonic() < deadline, "the stop was not raised after the import"


def test_a_stop_landing_in_numbas_own_code_is_raised_when_it_returns(handlers_kept):
    """numba's and llvmlite's Python code (loading or compiling a kernel), cut by a
    stop, left a half-built object whose finalizer crashed the process (a
    segmentation fault, once in 60 stops during the kernels' warm-up). A stop landing
    in a frame of theirs (here: code compiled under a file name in numba's package) is
    held back, and raised once control is back in the caller."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are installed in the main thread only")
    import os

    import numba

    inside = os.path.join(numba.__path__[0], "core", "held.py")
    code = compile("on_sigint(2, sys._getframe()); reached = True", inside, "exec")
    scope = {"on_sigint": signals._on_sigint, "sys": sys}
    deadline = time.monotonic() + 2.0
    with signals.handled(), pytest.raises(KeyboardInterrupt):
        exec(code, scope)  # "numba's" code runs to its end
        while time.monotonic() < deadline:  # and the stop comes in the caller
            sum(range(1000))
    assert scope.get("reached"), "the stop cut numba's code"
    assert time.monotonic() < deadline, "the stop was not raised after numba's code"


def test_a_stop_returned_as_another_error_is_the_stop(monkeypatch, capsys, handlers_kept):
    """numba's dispatcher returns a ``KeyboardInterrupt`` raised in a callback as
    ``SystemError: ... returned a result with an exception set``: the command reports
    it as the stop it is (status 130, one line), and a run in this process does not
    record it as the run's error."""
    from kalman_vs_infoset.experiments.limits import reraise_timeout

    def run(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("returned a result with an exception set") from exc

    _command_fake(monkeypatch, run)
    assert cli.main(["fake"]) == 130
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        "kvi fake: interrupted; finished runs are saved; rerun to resume"
    ], err
    with pytest.raises(KeyboardInterrupt):
        try:
            run(None)
        except Exception as exc:  # what a run's own handler does
            reraise_timeout(exc)


@pytest.mark.parametrize("handler", ["_on_sigint", "_on_sigterm"])
def test_a_signal_landing_inside_a_wait_on_workers_leaves_no_lock_held(handler, monkeypatch):
    """The regression behind a Ctrl-C that hung at exit: the handler raised while the
    command held the futures' locks in ``concurrent.futures.wait``, and the pool's
    manager thread blocked on them for good. The wait below takes every future's lock,
    as ``wait`` does, and the signal lands there; the stop must come after the wait
    with every lock free."""
    from concurrent.futures import ThreadPoolExecutor

    real_wait = executors.wait
    seen: list = []

    def wait_hit_by_a_signal(fs, **kw):
        real_wait(fs)  # all done first: no worker thread needs the locks below
        seen.extend(fs)
        locks = [f._condition for f in fs]
        for lock in locks:  # as wait's _AcquireFutures: no finally releases them
            lock.acquire()
        getattr(signals, handler)(signal.SIGINT, None)
        for lock in locks:
            lock.release()
        return real_wait(fs, **kw)

    monkeypatch.setattr(executors, "wait", wait_hit_by_a_signal)
    before = signal.getsignal(signal.SIGTERM)
    errors.clear_stop()
    try:
        with ThreadPoolExecutor(1) as ex, pytest.raises(KeyboardInterrupt) as stop:
            list(executors._pooled(ex, lambda c: [(j, {}) for j in c], [[0], [1]], 2, {}))
    finally:
        errors.clear_stop()
        signal.signal(signal.SIGTERM, before)  # the SIGTERM handler ignores a second one
    expected = errors.Terminated if handler == "_on_sigterm" else KeyboardInterrupt
    assert seen and stop.type is expected
    # every lock free for another thread (they are re-entrant for this one), as the
    # pool's manager thread needs them to set the results
    free: list[bool] = []

    def try_locks() -> None:
        for fut in seen:
            free.append(fut._condition.acquire(blocking=False))
            if free[-1]:
                fut._condition.release()

    checker = threading.Thread(target=try_locks)
    checker.start()
    checker.join()
    assert free and all(free), free
