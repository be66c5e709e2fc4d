"""Where the runner's tasks run: this process, local worker processes, or a Dask cluster.

Local pool workers exit when the command that started them dies (a SIGKILLed command
used to leave them running for good); a Dask cluster whose workers run other sources
than this process is refused before any run (their rows would carry this process's
code identity).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

from kalman_vs_infoset.estim import _kernels as _k
from kalman_vs_infoset.experiments import provenance
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.provenance import code_identity

#: how often a pool worker checks that its parent is alive (s)
WATCHDOG_S = 1.0


@contextmanager
def make_executor(workers: int | None = None, scheduler: str | None = None) -> Iterator[Executor]:
    """Local processes by default, a Dask cluster when ``scheduler`` is given."""
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise InputError(
                "--scheduler needs dask.distributed (pip install 'kalman-vs-infoset[cluster]')"
            ) from None
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            why = (str(exc).splitlines() or [type(exc).__name__])[0]
            raise InputError(f"cannot reach the Dask scheduler at {scheduler!r}: {why}") from None
        try:
            _check_workers_code(client, scheduler)
            yield client.get_executor()
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    _k.warm_up()  # forked workers inherit the loaded kernels
    pool = ProcessPoolExecutor(max_workers=n, initializer=_worker_init, initargs=(os.getpid(),))
    try:
        yield pool
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _worker_init(parent_pid: int) -> None:
    """A pool worker exits when its parent dies (a SIGKILLed command left its workers
    running for good): the kernel's parent-death signal on Linux, and a watchdog thread
    that sees the worker re-parented anywhere."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(WATCHDOG_S)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _check_workers_code(client, scheduler: str) -> None:
    """Refuse a cluster whose workers run other sources than this process: their rows
    would be recorded under this process's code identity."""
    here = code_identity()["sources_sha256"]
    try:
        theirs = client.run(provenance.sources_sha256)  # imported on each worker
    except Exception as exc:  # e.g. the package is not installed on a worker
        raise InputError(
            f"Dask workers at {scheduler} cannot run this package ({type(exc).__name__}: {exc})"
        ) from None
    for worker, h in sorted(theirs.items()):
        if h != here:
            raise InputError(
                f"Dask worker {worker} runs other code (sources {h[:12]}, here {here[:12]}); "
                "install the same version on every worker"
            )


@contextmanager
def executor_or(executor: Executor | None, workers, scheduler) -> Iterator[Executor]:
    if executor is not None:
        yield executor
    else:
        with make_executor(workers, scheduler) as ex:
            yield ex
