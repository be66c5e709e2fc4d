"""Where the runner's tasks run: this process, local worker processes, or a Dask cluster.

Local pool workers exit when the command that started them dies (a SIGKILLed command
used to leave them running for good); a Dask cluster whose workers run other sources
than this process is refused before any run (their rows would carry this process's
code identity).
"""

from __future__ import annotations

import gc
import os
import signal
import threading
import time
from collections.abc import Iterator
from concurrent.futures import (
    FIRST_COMPLETED,
    BrokenExecutor,
    CancelledError,
    Executor,
    ProcessPoolExecutor,
    wait,
)
from contextlib import contextmanager
from functools import partial
from typing import Any

from kalman_vs_infoset.experiments import provenance
from kalman_vs_infoset.experiments.errors import (
    InputError,
    check_stop,
    runs_text,
    stop_requested,
    stops_deferred,
)
from kalman_vs_infoset.experiments.limits import RunLimits, limited
from kalman_vs_infoset.experiments.provenance import code_identity
from kalman_vs_infoset.experiments.usage import usable_cpus
from kalman_vs_infoset.experiments.warm import exit_with_parent, warm_kernels

#: how often a pool worker checks that its parent is alive (s)
WATCHDOG_S = 1.0

#: chunks queued per local worker (the others are submitted as these finish)
IN_FLIGHT = 2

#: how long runs on a Dask cluster wait with no live worker before giving up (s)
NO_WORKER_TIMEOUT_S = 60.0

#: how long connecting to a Dask scheduler may take before it is refused (s)
CONNECT_TIMEOUT_S = 10.0


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
            _probe_scheduler(scheduler)
            client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S:g}s")
        except Exception as exc:  # noqa: BLE001 - whatever answers there, one line
            why = (str(exc).splitlines() or [""])[0] or type(exc).__name__
            raise InputError(f"cannot reach the Dask scheduler at {scheduler!r}: {why}") from None
        try:
            _check_workers_code(client, scheduler)
            yield client.get_executor()
        finally:
            client.close()
        return
    n = workers or usable_cpus()
    warm_kernels()  # forked workers inherit the loaded kernels
    # The parent's objects go to the collector's permanent generation before the fork:
    # a worker's collections would otherwise write to every one of them and copy the
    # parent's heap page by page (a few per cent of `kvi fig5`'s CPU time, measured).
    # No full collection first (Python's gc.freeze advice): it only frees a little
    # garbage, and cost 0.06 s a pool in `kvi fig5` and 0.2 s in a test process.
    gc.freeze()
    pool = ProcessPoolExecutor(max_workers=n, initializer=_worker_init, initargs=(os.getpid(),))
    # The pool's shutdown takes its locks and the futures': a second Ctrl-C must not
    # raise there (see errors.stops_deferred), so these steps defer the signals.
    try:
        yield pool
    except BaseException:  # Ctrl-C, SIGTERM, an error: the running chunks are not waited for
        with stops_deferred():
            _stop_workers(pool)
        raise
    else:
        if not stop_requested():
            # every chunk is done: the workers exit at once, and waiting for them counts
            # their CPU time in this process's usage (experiments.usage: a variant's cpu_s)
            with stops_deferred():
                pool.shutdown(wait=True)
    finally:
        with stops_deferred():
            pool.shutdown(wait=False, cancel_futures=True)
        gc.unfreeze()  # this process collects its objects again


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """End a pool's worker processes now (the command is stopping: their chunks are
    not finished, so nothing is lost that a rerun does not compute)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.kill()
        except (OSError, AttributeError):
            pass


def _worker_init(parent_pid: int) -> None:
    """A pool worker exits when its parent dies (a SIGKILLed command left its workers
    running for good): the kernel's parent-death signal on Linux, and a watchdog thread
    that sees the worker re-parented anywhere."""
    exit_with_parent(parent_pid)
    # Ctrl-C and SIGTERM are the command's to handle (it saves and stops the workers)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(WATCHDOG_S)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _probe_scheduler(address: str, timeout_s: float | None = None) -> None:
    """Raise unless a Dask scheduler answers the comm handshake at ``address`` within
    ``timeout_s`` (default :data:`CONNECT_TIMEOUT_S`). ``distributed.Client`` waits for
    the handshake without a time limit (a server that accepts and stays silent, e.g. an
    HTTP server on the dashboard's port, hung the command), and reads an HTTP reply as a
    frame length (it tried to allocate exabytes). The probe runs on a loop of its own,
    in a thread, so that a caller's running event loop (a notebook) is not in the way."""
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    timeout_s = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
    # the connection arguments the client takes from Dask's configuration (TLS
    # certificates: without them a tls:// scheduler was refused)
    args = Security().get_connection_args("client")

    async def handshake() -> None:
        comm = await asyncio.wait_for(connect(address, timeout=timeout_s, **args), timeout_s)
        await comm.close()

    failed: list[BaseException] = []

    def probe() -> None:
        try:
            asyncio.run(handshake())
        except BaseException as exc:  # noqa: BLE001 - reported to the caller below
            failed.append(exc)

    thread = threading.Thread(target=probe, name="kvi-scheduler-probe", daemon=True)
    thread.start()
    thread.join(timeout_s + 5.0)  # asyncio.wait_for ends it first; this is a backstop
    if thread.is_alive():
        raise TimeoutError(f"no handshake within {timeout_s:g} s")
    if failed:
        exc = failed[0]
        if isinstance(exc, asyncio.TimeoutError | TimeoutError):
            raise TimeoutError(f"no Dask handshake within {timeout_s:g} s (not a scheduler?)")
        if isinstance(exc, MemoryError):  # a reply read as the length of a frame
            raise ValueError("its reply is not Dask's protocol (not a scheduler?)")
        raise exc


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
    # a plug-in both sides have must be the same version (one a worker lacks fails its
    # runs there, by name, as an unknown estimator)
    mine = provenance.plugins_identity()
    for worker, plugins in sorted(client.run(provenance.plugins_identity).items()):
        for key in sorted(set(mine) & set(plugins)):
            if plugins[key] != mine[key]:
                raise InputError(
                    f"Dask worker {worker} runs another version of the estimator plug-in "
                    f"{key.split('/', 1)[1]!r}; install the same version on every worker"
                )


@contextmanager
def executor_or(executor: Executor | None, workers, scheduler) -> Iterator[Executor]:
    if executor is not None:
        yield executor
    else:
        with make_executor(workers, scheduler) as ex:
            yield ex


class WorkerLost(RuntimeError):
    """Runs neither finished nor failed: a worker process died, a run ran out of memory,
    or a Dask cluster had no live worker. Finished runs are saved, the lost ones are
    missing (a rerun computes them); the command exits with status 1."""


def oom_kills(vmstat: str = "/proc/vmstat") -> int | None:
    """How many processes the kernel's out-of-memory killer has ended since boot
    (Linux ``oom_kill``; None where the system does not say)."""
    try:
        with open(vmstat) as fh:
            for line in fh:
                if line.startswith("oom_kill "):
                    return int(line.split()[1])
    except (OSError, ValueError):
        return None
    return None


def _chunks(todo: list[int], size: int) -> list[list[int]]:
    chunks: dict[int, list[int]] = {}
    for j in todo:
        chunks.setdefault(j // size, []).append(j)
    return list(chunks.values())


def results(job, todo: list[int], executor, workers, scheduler, limits: RunLimits | None = None):
    """Yield each finished chunk's ``[(run, row), ...]`` whole: in order in this process
    for one local worker (so Ctrl-C stops between chunks), else as completed on the
    executor. A chunk is one value, so a command stopped while it takes the rows in
    saves whole chunks only. Local
    workers are capped at the number of chunks; runs lost to a dead worker or to memory
    are counted and raise :class:`WorkerLost` once the others are through."""
    chunks = _chunks(todo, job.chunk)
    task = partial(limited, job.task, limits) if limits else job.task
    n = min(workers or usable_cpus(), len(chunks))
    lost = {"dead": 0, "memory": 0}
    oom_before = oom_kills()
    # a memory limit is set in a worker process, never in this one: a library that fails
    # an allocation under it without raising (OpenBLAS exits, CPython can crash within an
    # import) then ends that worker, which is reported, not the command
    in_process = not (limits and limits.memory_mb is not None)
    if executor is None and scheduler is None and n == 1 and in_process:
        if limits:
            warm_kernels()  # loaded before the limits: each run is judged by its own cost
        for chunk in chunks:
            check_stop()
            try:
                pairs = task(chunk)
            except MemoryError:
                lost["memory"] += len(chunk)
                continue
            yield pairs
    else:
        with executor_or(executor, n, scheduler) as ex:
            window = len(chunks) if scheduler or executor else IN_FLIGHT * n
            yield from _pooled(ex, task, chunks, window, lost)
    why = [f"{runs_text(lost['dead'])} lost to a dead worker"] if lost["dead"] else []
    if lost["dead"] and oom_before is not None and (oom_kills() or 0) > oom_before:
        # a worker killed by the kernel for memory raises no MemoryError: it just dies
        why[0] += " (the system's out-of-memory killer ended a process meanwhile: try "
        why[0] += "fewer --workers or smaller options)"
    if lost["memory"]:
        why.append(f"{runs_text(lost['memory'])} out of memory (try fewer --workers)")
    if why:
        raise WorkerLost(f"{'; '.join(why)}; finished runs are saved; rerun the same command")


def _pooled(ex: Executor, task, chunks: list[list[int]], window: int, lost: dict[str, int]):
    """The rows of ``chunks`` on ``ex`` (a list per chunk), at most ``window`` chunks
    queued at a time."""
    queue = iter(chunks)
    pending: dict[Any, list[int]] = {}
    idle_since = None

    def refill() -> None:
        while len(pending) < window:
            chunk = next(queue, None)
            if chunk is None:
                return
            try:
                pending[ex.submit(task, chunk)] = chunk
            except (BrokenExecutor, RuntimeError):  # the pool is broken: lost, not failed
                lost["dead"] += len(chunk) + sum(map(len, queue))
                return

    # The waits, submissions and results hold the futures' and the pool's locks: a
    # signal only records the stop there, raised by check_stop within a second.
    with stops_deferred():
        refill()
    check_stop()
    while pending:
        with stops_deferred():
            done, _ = wait(pending, timeout=1.0, return_when=FIRST_COMPLETED)
        check_stop()
        if not done:
            if _live_workers(ex) == 0:
                idle_since = idle_since or time.monotonic()
                if time.monotonic() - idle_since > NO_WORKER_TIMEOUT_S:
                    left = sum(map(len, pending.values())) + sum(map(len, queue))
                    raise WorkerLost(
                        f"no live Dask worker for {NO_WORKER_TIMEOUT_S:g} s ({runs_text(left)} not "
                        "run); finished runs are saved; start workers and rerun the same command"
                    )
            else:
                idle_since = None
            continue
        for fut in done:
            chunk = pending.pop(fut)
            try:
                with stops_deferred():
                    pairs = fut.result()
            except InputError:
                raise
            except (BrokenExecutor, CancelledError):
                lost["dead"] += len(chunk)  # a worker died: missing, not failed (resumable)
                continue
            except MemoryError:
                lost["memory"] += len(chunk)
                continue
            except Exception as exc:  # the task itself raised outside the runs
                row = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
                pairs = [(j, dict(row)) for j in chunk]
            yield pairs
        with stops_deferred():
            refill()


def _live_workers(ex: Executor) -> int | None:
    """Workers of a Dask executor's cluster (None for other executors)."""
    client = getattr(ex, "_client", None)
    if client is None:
        return None
    try:
        return len(client.scheduler_info().get("workers", {}))
    except Exception:  # noqa: BLE001 - the scheduler itself is gone
        return 0
