"""Output files: written whole or not at all, never over something that is not a file.

Every file amilpy writes (CSV, PNG, reports) goes through `atomic_open`: the data
go to a hidden temporary beside the target, which replaces the target only once
it is complete, so a reader sees the old file or the new one, never half of one.
The temporary is removed on every way out that Python sees (an error, Ctrl-C,
SIGTERM/SIGHUP, which the command line turns into an interrupt).

What is at the target decides what happens:
- nothing, or a regular file: written (an existing file keeps its mode);
- a symbolic link: written through, i.e. the file it points to is replaced and the
  link stays (a dangling link gets its file created);
- a directory, FIFO, device or socket: refused with an `OutputError`, never replaced.

Any failure (a read-only folder, a full disk, a path through a file) is an
`OutputError` naming the path and the reason; the command line reports it and
exits 4 after writing the outputs it can.
"""

from __future__ import annotations

import errno
import os
import stat
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from typing import IO

from ..diagnostics import AmilError


class OutputError(AmilError):
    """An output could not be written: `path` and `reason` say which and why."""

    def __init__(self, path: str, reason: str) -> None:
        self.reason = reason
        super().__init__(f"cannot write {path}: {reason}", path)

    def render(self) -> str:
        return f"amilpy: {self}"


_KINDS = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _reason(exc: OSError) -> str:
    if exc.errno == errno.EFBIG:
        return "the file is larger than this process may write (file size limit)"
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    return exc.strerror or str(exc)


def ensure_directory(directory: str) -> str:
    """Make `directory` (and its parents) if needed; an OutputError if it cannot be."""
    if os.path.exists(directory) and not os.path.isdir(directory):
        raise OutputError(directory, "it is not a directory")
    try:
        os.makedirs(directory, exist_ok=True)
    except OSError as exc:
        raise OutputError(directory, _reason(exc)) from None
    return directory


def resolve_target(path: str) -> str:
    """The file that writing `path` replaces (a symbolic link is followed); an
    OutputError if something other than a regular file is there."""
    target = os.path.realpath(path)
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise OutputError(path, _reason(exc)) from None
    if mode is not None:
        if stat.S_ISDIR(mode):
            raise OutputError(path, "it is a directory; give a file name")
        for test, what in _KINDS:
            if test(mode):
                raise OutputError(path, f"it is {what}, not a regular file (amilpy never "
                                        "replaces one)")
    return target


def _file_mode(path: str) -> int:
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


# names of a stream the shell opened (`--csv /dev/stdout > out.txt`): written where
# they stand, appended to; a temporary renamed onto what they lead to would replace
# the shell's file (and the printout in it) with an unlinked one
STREAMS = ("/dev/stdout", "/dev/stderr", "/dev/null")
STREAM_FOLDERS = ("/dev/fd/", "/proc/self/fd/")


def _own_stream(path: str):
    """sys.stdout or sys.stderr if `path` names the file it writes to, else None."""
    for stream in (sys.stdout, sys.stderr):
        try:
            a, b = os.stat(path), os.fstat(stream.fileno())
        except (OSError, ValueError, AttributeError):
            continue
        if (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino) and hasattr(stream, "buffer"):
            return stream
    return None


def to_devnull(stream) -> None:
    """What is left to write to `stream` goes nowhere (its reader has gone)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def is_stream(path: str) -> bool:
    path = os.path.abspath(path)
    return path in STREAMS or path.startswith(STREAM_FOLDERS)


@contextmanager
def atomic_open(path: str, text: bool = False, encoding: str = "utf-8",
                newline: str | None = "") -> Iterator[IO]:
    """Open a temporary beside `path` for writing; on a clean exit it replaces
    `path` (binary unless `text`). Rows can be streamed into it. A stream's name
    (`is_stream`) is written in place."""
    if is_stream(path):
        own = _own_stream(path)
        try:
            if own is not None:  # (through the same file offset as the printout)
                own.flush()
                out = own if text else own.buffer
                yield out
                out.flush()
            else:
                with open(path, "a" if text else "ab",
                          **({"encoding": encoding, "newline": newline} if text else {})) \
                        as fh:
                    yield fh
        except BrokenPipeError:  # (the reader went away, as `| head` does: quietly)
            to_devnull(own)
        except OSError as exc:
            raise OutputError(path, _reason(exc)) from None
        return
    ensure_directory(os.path.dirname(os.path.abspath(path)))
    target = resolve_target(path)
    folder = os.path.dirname(target) or "."
    if target != os.path.abspath(path) and not os.path.isdir(folder):
        # (a symbolic link whose target's folder is missing: not made for it)
        raise OutputError(path, f"it is a symbolic link to {target}, whose folder does not "
                                "exist")
    directory = ensure_directory(folder)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(target)}.", suffix=".amilpy-tmp",
                                   dir=directory)
    except OSError as exc:
        raise OutputError(path, _reason(exc)) from None
    try:
        with os.fdopen(fd, "w" if text else "wb",
                       **({"encoding": encoding, "newline": newline} if text else {})) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp makes the file private (0600); the result is an ordinary file,
        # with the mode a plain open() would give it, or the one it had before
        os.chmod(tmp, _file_mode(target))
        os.replace(tmp, target)
    except OSError as exc:
        _remove(tmp)
        raise OutputError(path, _reason(exc)) from None
    except BaseException:
        _remove(tmp)
        raise


def _remove(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except OSError:
        pass


def atomic_write(path: str, data: bytes) -> None:
    """Write a whole file so that it is either the old one or the complete new one."""
    with atomic_open(path) as fh:
        fh.write(data)
