"""Results on a disk: written whole or not at all, and a full disk said plainly.

Every result is written into a temporary file beside it and renamed into
place once complete (:func:`atomic_output`, :func:`write_bytes`,
:func:`write_text`): a job killed or out of disk space never leaves a
half-written file under a result's name, and Snakemake's own removal of a
failed job's outputs finds nothing half-done to miss. A write that fails
for want of space is a :class:`NoSpace` error naming the file, the bytes it
needed and those left, which a job prints in one line
(:func:`rocklab.jobs.start`).
"""

from __future__ import annotations

import errno
import glob
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Self, TypeAlias

#: A path as the callers give it: a string or a path-like object.
StrPath: TypeAlias = str | os.PathLike[str]

#: The errors of a write that found no room: the disk full, the user's quota spent.
SPACE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT})


def _size(n: float) -> str:
    """A number of bytes for a person: 1.2 MB, 830 kB, 12 B."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n:.0f} B"


class NoSpace(OSError):
    """A result the disk had no room for.

    ``path``: the file that could not be written; ``needed``: the bytes it
    takes (an upper bound where it is compressed as it is written; None if
    not known); ``free``: the bytes left on its filesystem.
    """

    def __init__(self, path: StrPath, needed: int | None, free: int) -> None:
        self.path, self.needed, self.free = Path(path), needed, free
        super().__init__(errno.ENOSPC, str(self), str(path))

    def __str__(self) -> str:
        need = f"it needs up to {_size(self.needed)}, " if self.needed else ""
        return (
            f"no space left to write {self.path}: {need}{_size(self.free)} free on its disk. "
            "Free some space and run the same command again: nothing half-written is left behind."
        )

    def __reduce__(self) -> tuple[type[Self], tuple[Path, int | None, int]]:
        return type(self), (self.path, self.needed, self.free)


def _is_out_of_space(exc: BaseException, folder: Path, needed: int | None) -> bool:
    """Whether a failed write failed for want of space: the error says so, or
    (a library that reports a bare I/O error, as netCDF-C does) the folder's
    filesystem has less room than the write needed, or none to speak of."""
    if isinstance(exc, OSError) and exc.errno in SPACE_ERRNOS:
        return True
    if not isinstance(exc, (OSError, RuntimeError)):
        return False
    free = free_bytes(folder)
    return free is not None and (free < (needed or 0) or free < SPACE_FLOOR)


def no_space(exc: BaseException, path: StrPath, needed: int | None = None) -> NoSpace | None:
    """The :class:`NoSpace` that a failed write of ``path`` stands for, None if it failed for another reason."""
    path = Path(path)
    if not _is_out_of_space(exc, path.parent, needed):
        return None
    return NoSpace(path, needed, free_bytes(path.parent) or 0)


#: Free bytes below which a failed write is taken for a full disk whatever it needed.
SPACE_FLOOR = 64 * 1024
#: The process's umask, read once (reading it means setting it): the mode of a new file.
_UMASK = os.umask(0)
os.umask(_UMASK)


@contextmanager
def atomic_output(path: StrPath, needed: int | None = None) -> Iterator[Path]:
    """A temporary file beside ``path``, renamed to ``path`` once the block ends without error.

    The file gets the mode of any new file (not ``mkstemp``'s 0600). On an
    error the temporary file is removed; an error for want of space
    (:func:`no_space`) becomes :class:`NoSpace`, naming ``path`` and
    ``needed`` (bytes, if the caller knows them), and the space free once
    the temporary file is gone. A temporary file that a killed writer left
    behind (``mkstemp``'s eight random characters) goes with the next write
    of ``path``.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        for stale in path.parent.glob(f".{glob.escape(path.name)}.{'?' * 8}.tmp"):
            stale.unlink(missing_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        if (full := no_space(exc, path, needed)) is not None:
            raise full from exc
        raise
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except Exception as exc:
        if os.path.exists(tmp):
            os.remove(tmp)
        if (full := no_space(exc, path, needed)) is not None:
            raise full from exc
        raise
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def free_bytes(folder: StrPath) -> int | None:
    """Bytes free on the filesystem of ``folder`` (or of its nearest existing parent), None if it cannot be told."""
    folder = Path(folder).absolute()
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


def write_bytes(path: StrPath, data: bytes) -> None:
    """Write ``data`` to ``path`` through :func:`atomic_output`."""
    with atomic_output(path, len(data)) as tmp:
        tmp.write_bytes(data)


def write_text(path: StrPath, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_output`."""
    write_bytes(path, text.encode())
