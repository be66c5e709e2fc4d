"""Atomic file writes (a reader, or a resumed run, never sees a half-written file) and
one writer per results file (an advisory lock beside it)."""

from __future__ import annotations

import errno
import os
import sys
import tempfile
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
    onto ``path`` (atomic on POSIX and Windows); the temporary file never survives and
    the file gets the permissions the umask gives new files."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=path.name, suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        # mkstemp makes the file 0600; a data file gets the mode any new file would
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


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
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666 & ~_umask())
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
