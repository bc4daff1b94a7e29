"""Reading files from data: regular files only, and small ones where a cap is natural.

A FIFO given as a scenario file blocks a reader forever; a table linked to ``/dev/zero`` reads without end.
Every file simrig reads from a user's data goes through :func:`open_regular` (or :func:`read_capped`), which
opens without blocking, checks on the open file that it is a regular file (a link is followed to what it names,
which must be a regular file too) and refuses anything else in one line naming the file. Text data files
(TOML, JSON, manifests) are capped at :data:`MAX_DATA_FILE_BYTES`.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import SimrigError

MAX_DATA_FILE_BYTES = 8 * 2**20
"""[bytes] the largest scenario, suite, search space, replay file, dataset manifest, side file or export marker
simrig reads (the shipped ones are under 20 KiB)."""


READ_CHUNK_BYTES = 2**20
"""[bytes] what a capped read asks the file for at a time."""


class UnreadableFileError(SimrigError):
    """A file is not a regular file, or is larger than a data file may be; the message names it."""


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a folder")):
        if test(mode):
            return name
    return "not a regular file"


def open_regular(path: Path | str, what: str, error: type[Exception] = UnreadableFileError):
    """``path`` opened for binary reading, or ``error`` (one line naming ``what`` and the path) when it is a
    FIFO, a device, a socket or a folder (or a link to one). Opening never blocks. ``FileNotFoundError`` and
    other ``OSError`` pass through for the caller to word."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise error(f"{what} {str(path)!r} is {_kind(mode)}, not a regular file")
        os.set_blocking(descriptor, True)
    except BaseException:
        os.close(descriptor)
        raise
    return os.fdopen(descriptor, "rb")


def check_regular(path: Path | str, what: str, error: type[Exception] = UnreadableFileError) -> None:
    """Raise ``error`` unless ``path`` is a regular file (see :func:`open_regular`); reads nothing."""
    with open_regular(path, what, error):
        pass


def read_capped(path: Path | str, what: str, error: type[Exception] = UnreadableFileError,
                max_bytes: int = MAX_DATA_FILE_BYTES) -> bytes:
    """The bytes of the regular file ``path``, or ``error`` when it is not one or holds more than
    ``max_bytes``."""
    data = bytearray()
    with open_regular(path, what, error) as handle:
        while len(data) <= max_bytes:  # by chunks: read(max_bytes + 1) reserves all of it up front, which a
            chunk = handle.read(min(READ_CHUNK_BYTES, max_bytes + 1 - len(data)))  # memory limit refuses
            if not chunk:
                break
            data += chunk
    if len(data) > max_bytes:
        raise error(f"{what} {str(path)!r} is larger than {max_bytes / 2**20:g} MiB, more than a {what} may be")
    return bytes(data)


def read_json(path: Path | str, what: str, error: type[Exception] = UnreadableFileError,
              max_bytes: int = MAX_DATA_FILE_BYTES):
    """The JSON document in the regular file ``path`` (:func:`read_capped`), or ``error`` naming ``what`` and the
    file when it is not UTF-8 JSON, is nested too deeply, or holds NaN or Infinity (not JSON, though Python's
    reader takes them, and nothing simrig writes holds them). A missing file is :class:`FileNotFoundError`."""
    import json

    def not_a_number(constant: str):
        raise ValueError(f"{constant} is not a JSON number (numbers must be finite)")

    data = read_capped(path, what, error, max_bytes)
    try:
        return json.loads(data.decode("utf-8"), parse_constant=not_a_number)
    except (ValueError, UnicodeDecodeError) as problem:
        raise error(f"{path}: {what} is not valid JSON ({problem})") from None
    except RecursionError:
        raise error(f"{path}: {what} is nested too deeply to be one") from None
