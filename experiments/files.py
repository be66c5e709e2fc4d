"""Atomic file writes (a reader, or a resumed run, never sees a half-written file) and
one writer per results file (an advisory lock beside it)."""

from __future__ import annotations

import errno
import glob
import os
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows: no advisory locks
    fcntl = None  # type: ignore[assignment]


def _umask() -> int:
    mask = os.umask(0)  # reading the umask means setting it: put it straight back
    os.umask(mask)
    return mask


def atomic_write(path: Path, write: Callable[[str], object]) -> None:
    """Call ``write(tmp)`` on a temporary file beside ``path``, then ``os.replace`` it
    onto ``path`` (atomic on POSIX and Windows); the file gets the permissions the umask
    gives new files.

    The temporary file is flushed to disk before the rename, and the folder after it,
    so that a power loss leaves the old file or the new one, never an empty one. The
    temporary file is hidden (``.<name>.<pid>.<random>.tmp``: Parquet readers of the
    folder skip names starting with a dot) and removed on any error; one left by a
    process that was killed meanwhile (``kill -9`` between the write and the rename) is
    removed by the next write of the same file, once its process is gone (a complete
    leftover table read as a second copy of its runs).
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(path)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent
    )
    os.close(fd)
    try:
        write(tmp)
        # mkstemp makes the file 0600; a data file gets the mode any new file would
        os.chmod(tmp, 0o666 & ~_umask())
        _sync(tmp)  # its bytes on disk before the name points at them (power loss)
        os.replace(tmp, path)
        _sync(path.parent)  # and the rename itself
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _sync(path: str | Path) -> None:
    """``fsync`` a file or a folder, where the system allows it (a folder cannot be
    opened on Windows; some file systems refuse to sync one: best effort there)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: what a read-only folder (or one without write permission) answers a write with
_READ_ONLY = (errno.EROFS, errno.EACCES, errno.EPERM)


def derived_write(path: Path, write: Callable[[str], object]) -> bool:
    """:func:`atomic_write` of a file derived from the runs' own tables (a combined
    table, a summary, a figure): in a folder the system refuses to write (read-only,
    no permission) it is skipped with one warning, so that a complete, read-only
    results folder can be summarised again. Returns whether the file was written. (A
    runs' table is written with :func:`atomic_write`: a run that cannot be saved is an
    error.)"""
    try:
        atomic_write(path, write)
    except OSError as exc:
        if exc.errno not in _READ_ONLY:
            raise
        warnings.warn(f"{path} not written ({exc.strerror}); the summary is printed",
                      RuntimeWarning, stacklevel=2)  # fmt: skip
        return False
    return True


def _remove_stale_temporaries(path: Path) -> None:
    """Remove the temporary files of ``path`` whose writing process no longer runs."""
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        pid = tmp.name[len(path.name) + 2 :].split(".", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            try:
                tmp.unlink()
            except OSError:  # removed meanwhile, or not ours to remove: harmless
                pass


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. another user's process: it exists
        return True
    return True


@contextmanager
def exclusive(path: Path, what: str) -> Iterator[None]:
    """Hold the advisory lock of ``path`` (``fcntl.flock`` on ``.<name>.lock`` beside it)
    while writing it: a second command on the same file waits for the first (one line
    on stderr says so) and then reads what the first wrote, so no finished run is lost
    to interleaved saves. The lock file is removed on release; a lock taken on a file
    that its holder has just removed is taken again on the new one. Where ``fcntl`` does
    not exist (Windows) nothing is locked."""
    if fcntl is None:
        yield
        return
    lock = path.with_name(f".{path.name}.lock")  # hidden: Parquet readers of the folder skip it
    told = False
    fd: int | None  # None: the file system cannot lock
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666 & ~_umask())
        except OSError as exc:  # said of the folder: the lock's name is ours, not the user's
            why = f"{exc.strerror or exc}: cannot write a file in this folder"
            raise OSError(exc.errno, why, str(path.parent)) from None
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                if not told:
                    holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
                    print(
                        f"{what}: {path.name} is being written by another command "
                        f"(pid {holder}); waiting for it to finish",
                        file=sys.stderr,
                        flush=True,
                    )
                    told = True
                fcntl.flock(fd, fcntl.LOCK_EX)  # Ctrl-C or SIGTERM interrupts the wait
            try:
                current = os.path.samestat(os.fstat(fd), os.stat(lock))
            except FileNotFoundError:
                current = False
        except OSError as exc:
            os.close(fd)
            if exc.errno not in _NO_LOCKS:
                raise
            fd = None  # a file system without locks (some NFS mounts): write unlocked
            break
        except BaseException:
            os.close(fd)
            raise
        if current:
            break
        os.close(fd)  # its holder removed it while we waited: lock the file there now
    if fd is None:
        _unlink(lock)
        print(f"{what}: {lock.parent} cannot lock files; writing unlocked", file=sys.stderr)
        yield
        return
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    finally:
        _unlink(lock)
        os.close(fd)  # releases the lock


#: errors of ``flock`` on a file system that has no locks
_NO_LOCKS = (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS)


def _unlink(path: Path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
