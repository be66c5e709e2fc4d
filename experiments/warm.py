"""Loading the compiled (numba) kernels before the runs, and compiling them side by side
on a first run.

A Monte Carlo pool's parent loads every kernel of the intercept estimators and the
truth before it forks, so that the workers inherit them (:func:`warm_kernels`). On the
first run after an install the cache is empty and loading them means compiling them:
about half a minute of CPU time, of which the node set's kernels are about two thirds.
A helper process then compiles the other group (:data:`WARM_UPS`) into the cache while
this one compiles the node set's, and this one loads the helper's from the cache: the
first run waits for the larger group instead of both. The helper ends with this process
(a stopped command leaves no compiler behind), and a helper that fails costs nothing but
the time: the warm-ups here compile whatever is not in the cache.
"""

from __future__ import annotations

import importlib
import io
import json
import os
import signal
import subprocess
import sys

from kalman_vs_infoset import _numba_cache

#: the modules whose ``warm_up()`` loads (or compiles) the kernels, in two groups of
#: similar compile cost: this process takes the first, a helper the second on a first
#: run (``tests/compile_kernels.py`` compiles the same groups before the tests)
WARM_UPS: tuple[tuple[str, ...], ...] = (
    ("kalman_vs_infoset.estim.intercept.nodeset.estimator",),
    (
        "kalman_vs_infoset.estim.common._kernels",
        "kalman_vs_infoset.estim.intercept.kinematic",
        "kalman_vs_infoset.guidance.intercept._kepler",
    ),
)

_HELPER = (
    "import sys\n"
    "from kalman_vs_infoset.experiments.warm import compile_aside\n"
    "compile_aside(int(sys.argv[1]), sys.argv[2:])\n"
)


def warm_kernels(groups: tuple[tuple[str, ...], ...] = WARM_UPS, aside: bool | None = None) -> None:
    """Load the kernels of ``groups`` in this process (from numba's on-disk cache, or
    compiled once), and the libraries every run imports at its end, so that forked
    workers inherit them instead of each importing them on its first run
    (scipy.optimize: 0.3 CPU-s a worker).

    ``aside`` (default: when the cache lacks the package's kernels and this process may
    use more than one CPU): the groups after the first are compiled by a helper process
    while this one runs the first group's warm-ups; then their warm-ups load them."""
    import scipy.optimize  # noqa: F401 - the closest approach's minimize_scalar

    if aside is None:
        aside = _first_compile()
    helper = _start_helper([m for g in groups[1:] for m in g]) if aside else None
    try:
        for module in groups[0]:
            _warm(module)
        if helper is not None:
            _join(helper)
    except BaseException:  # Ctrl-C, SIGTERM or an error: the helper stops with us
        if helper is not None:
            _stop(helper)
        raise
    for group in groups[1:]:
        for module in group:
            _warm(module)


def _warm(module: str) -> None:
    importlib.import_module(module).warm_up()


def _first_compile() -> bool:
    """Whether the kernels will compile here (the cache does not hold them) with a
    second CPU free to share the work."""
    from kalman_vs_infoset.experiments.progress import compiled_kernels_cached
    from kalman_vs_infoset.experiments.usage import usable_cpus

    return usable_cpus() > 1 and compiled_kernels_cached() is False


def _start_helper(modules: list[str]) -> subprocess.Popen | None:
    """The helper compiling ``modules``' kernels, or None if it cannot start (the
    warm-ups here then compile them)."""
    if not modules:
        return None
    try:
        return subprocess.Popen(
            [sys.executable, "-c", _HELPER, str(os.getpid()), *modules],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
            text=True,
        )  # fmt: skip
    except OSError:
        return None


def _join(helper: subprocess.Popen) -> None:
    """Wait for the helper; its compilations count in this command's compile notice."""
    out, _ = helper.communicate()
    if helper.returncode != 0:
        return  # what it did not compile, the warm-ups here compile
    try:
        done = json.loads(out.strip().splitlines()[-1])
        _numba_cache.note_compiled_aside(int(done["kernels"]), float(done["cpu_s"]))
    except (IndexError, KeyError, TypeError, ValueError):
        pass


def _stop(helper: subprocess.Popen) -> None:
    try:
        helper.kill()
        helper.wait()
    except OSError:
        pass


def exit_with_parent(parent_pid: int) -> None:
    """This process exits when ``parent_pid`` dies: the kernel's parent-death signal on
    Linux (SIGKILL), and an exit now if the parent is already gone."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)


def compile_aside(parent_pid: int, modules: list[str]) -> None:
    """The helper's work (a separate process): run the warm-ups of ``modules``, which
    compile their kernels into the cache, and print one JSON line of the compilations
    and their CPU time."""
    exit_with_parent(parent_pid)
    # a Ctrl-C at the terminal reaches this process too: the parent stops it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    notice = _numba_cache.CompileNotice(stream=io.StringIO()).install()  # counts, says nothing
    for module in modules:
        _warm(module)
    print(json.dumps({"kernels": notice.kernels, "cpu_s": notice.cpu_s}), flush=True)
