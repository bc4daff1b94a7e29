"""Where simrig may write: checked before any work, so a bad ``--out`` / ``--json`` costs nothing and harms nothing.

An output path is refused when it is the file system's root or the home folder, lies in a system folder
(``/proc``, ``/etc``, ...), under an existing file, inside one of the command's inputs (a dataset folder, a
tracks folder) or around one of them (an output folder that would hold, and on ``--overwrite`` delete, the
input). A command that writes several files into its folder (run, bench, search, report) writes only into a
new or empty folder or one it made before (:func:`check_own_folder`), and holds a lock on it while it works
(:func:`folder_lock`). Partial folders are named per process and carry a marker file, so two commands writing
to the same place never share one and a user's folder that merely looks like one is never removed.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import shutil
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import SimrigError

if TYPE_CHECKING:
    import pyarrow as pa
from ..reading import read_capped

SYSTEM_FOLDERS = ("/proc", "/sys", "/dev", "/etc", "/boot", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/usr",
                  "/var/lib", "/var/log")
"""Folders no simrig output belongs in (the file system's root itself included)."""


class OutputPathError(SimrigError):
    """An output path simrig must not write to; the message names the option and the path."""


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_output_path(path: Path | str, *, what: str, inputs: Iterable[Path | str | None] = (),
                      folder: bool = True) -> Path:
    """Refuse ``path`` (named ``what``, e.g. ``--out``) as an output; returns it unchanged when it may be written.

    ``inputs`` are the paths the command reads (``None`` entries are skipped); ``folder`` says whether the
    output is a folder (an existing file there is refused) or a file (an existing folder there is refused).
    The nearest existing folder above ``path`` must be writable: every output is written beside its place and
    renamed into it, so a read-only working folder is refused before any work."""
    path = Path(path)
    if folder and path.is_symlink():  # a file output replaces a planted link; a folder's contents would be moved
        raise OutputPathError(f"{what} {str(path)!r} is a symbolic link; simrig does not write through links: name "
                              "the folder itself, or another")
    resolved = path.resolve()
    if resolved == Path(resolved.anchor):
        raise OutputPathError(f"{what} {str(path)!r} is the root of the file system")
    if folder and resolved == Path.home().resolve():
        raise OutputPathError(f"{what} {str(path)!r} is your home folder; name a folder inside it")
    for system in SYSTEM_FOLDERS:
        if _inside(resolved, Path(system)):
            raise OutputPathError(f"{what} {str(path)!r} is in the system folder {system}")
    for parent in resolved.parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputPathError(f"{what} {str(path)!r} is under {str(parent)!r}, which is a file")
            if not os.access(parent, os.W_OK | os.X_OK):  # before any work: the output is made beside its place
                raise OutputPathError(f"{what} {str(path)!r}: cannot write in {str(parent)!r} (a read-only file "
                                      "system, or no permission); choose a folder you can write to")
            break
    if resolved.exists():
        if folder and not resolved.is_dir():
            raise OutputPathError(f"{what} {str(path)!r} is a file, not a folder")
        if not folder and resolved.is_dir():
            raise OutputPathError(f"{what} {str(path)!r} is a folder, not a file")
        if not folder and not resolved.is_file():
            raise OutputPathError(f"{what} {str(path)!r} is a FIFO, a device or a socket, not a file to replace")
    for source in inputs:
        if source is None:
            continue
        source_resolved = Path(source).resolve()
        if _inside(resolved, source_resolved):
            raise OutputPathError(f"{what} {str(path)!r} is inside the input {str(source)!r}; write elsewhere")
        if folder and source_resolved.is_relative_to(resolved):
            raise OutputPathError(f"{what} {str(path)!r} holds the input {str(source)!r}; write elsewhere")
    return path


LOCK_FILE = ".lock"
"""Held (``flock``) by the command writing into a folder; not counted as content."""
PARTIAL_MARKER = ".simrig-partial"
"""The file inside every partial folder simrig makes: only a folder holding it is ever removed as stale."""


def check_own_folder(out: Path, *, what: str, marker: str, made: Iterable[str] = (),
                     marker_keys: Iterable[str] = (), hint: str = "") -> None:
    """Refuse ``out`` as the folder of a command that writes several files there unless it is new or empty,
    holds ``marker`` (the file that command writes first, e.g. ``bench.json``; when ``marker_keys`` are given,
    a JSON object with those keys — a user's own file of that name is not simrig's), or holds only names in
    ``made`` (what the command itself writes before its marker) and hidden partial folders. ``what`` names the
    command's folder in the message (e.g. ``"bench folder"``); ``hint`` (``"; it is …"``) says what the folder
    is when the caller can tell."""
    if not out.is_dir():
        return
    made = set(made)
    entries = [entry.name for entry in out.iterdir() if entry.name != LOCK_FILE]
    if not entries or (marker in entries and _is_marker(out / marker, tuple(marker_keys))):
        return
    if all(name in made or (name.startswith(".") and ".partial" in name) for name in entries):
        return
    raise OutputPathError(f"{what} {str(out)!r} is not empty and holds no {marker}{hint}: simrig writes only into a "
                          f"new or empty folder or one it made; choose another --out")


def check_no_links(root: Path, relative: str | Path, *, what: str) -> None:
    """Refuse to write at ``root / relative`` when ``relative`` passes through a symbolic link (each of its folders
    and itself, ``root`` excepted: the user named it): a link planted in a folder simrig made would carry the write
    elsewhere. ``what`` names ``root`` in the message."""
    path = root
    for part in Path(relative).parts:
        path = path / part
        if path.is_symlink():
            raise OutputPathError(f"{what} {str(root)!r}: {path.relative_to(root)} is a symbolic link; simrig writes "
                                  "nothing through a link in a folder it made: remove the link")


def _is_marker(path: Path, keys: tuple[str, ...]) -> bool:
    """Whether ``path`` is a marker simrig wrote: any entry when no ``keys`` are asked for, else a regular JSON
    file holding an object with every key."""
    if not keys:
        return True
    try:
        document = json.loads(read_capped(path, path.name, OutputPathError))
    except (OSError, ValueError, OutputPathError):
        return False
    return isinstance(document, dict) and all(key in document for key in keys)


@contextmanager
def folder_lock(out: Path, command: str) -> Iterator[None]:
    """Hold ``OUT/.lock`` for this process while ``command`` (e.g. ``"simrig bench"``) writes into ``out``: a
    second command in the same folder stops at once, naming it."""
    handle = _open_for_writing(out / LOCK_FILE, "a+")
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise OutputPathError(f"{str(out)!r} is in use by another {command}; wait for it or choose another "
                                  "--out") from None
        yield
    finally:
        handle.close()


def _open_for_writing(path: Path, mode: str = "w", **options):
    """``open(path, mode)`` that refuses to follow a symbolic link at ``path`` (``O_NOFOLLOW``): a link
    planted where simrig writes is an :class:`OutputPathError` naming it, never a write to what it points at."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC
    flags |= os.O_APPEND if mode.startswith("a") else os.O_TRUNC
    if "+" in mode:
        flags = (flags & ~os.O_WRONLY) | os.O_RDWR
    try:
        descriptor = os.open(path, flags, 0o666)
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise OutputPathError(f"{str(path)!r} is a symbolic link; simrig does not write through links") from None
        raise
    return os.fdopen(descriptor, mode, **options)


@contextmanager
def atomic_file(path: Path) -> Iterator[Path]:
    """Write one file atomically: yields a temporary sibling (``.NAME.partial-PID``) for the caller to write
    (``pq.write_table``, ``savefig``, ...); on success it is flushed to disk and renamed to ``path``, replacing
    a file or a symbolic link there (the rename never follows a link, so nothing is written through one); on an
    exception it is removed. A link planted at the temporary name is removed before writing."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.partial-{os.getpid()}")
    if temporary.is_symlink():
        temporary.unlink()
    try:
        yield temporary
        with open(temporary, "rb") as handle:
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """``data`` into ``path`` through :func:`atomic_file`."""
    with atomic_file(path) as temporary, _open_for_writing(temporary, "wb") as handle:
        handle.write(data)


def write_text_atomic(path: Path, text: str) -> None:
    """``text`` as UTF-8 into ``path`` through :func:`atomic_file`."""
    write_bytes_atomic(path, text.encode("utf-8"))


def save_figure(figure, path: Path, **options) -> Path:
    """A matplotlib ``figure`` saved to ``path`` through :func:`atomic_file` (format from the suffix, PNG when
    it has none); ``options`` go to ``savefig``."""
    path = Path(path)
    with atomic_file(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".").lower() or "png", **options)
    return path


def partial_sibling(out: Path) -> Path:
    """The hidden partial folder of ``out`` for this process: ``.<name>.partial-<pid>`` next to it."""
    return out.parent / f".{out.name}.partial-{os.getpid()}"


def make_partial(partial: Path) -> None:
    """Create the partial folder ``partial`` (:func:`partial_sibling`) with its :data:`PARTIAL_MARKER`."""
    partial.mkdir()
    (partial / PARTIAL_MARKER).write_text(f"{os.getpid()}\n")


def publish(partial: Path, out: Path, written_by_simrig: Callable[[Path], bool]) -> list[Path]:
    """Make the finished ``partial`` folder ``out``. An earlier ``out`` is replaced, but only what simrig wrote
    there is deleted: every file of it for which ``written_by_simrig(relative path)`` is false (a user's notes,
    a mosaic) is moved into the new folder at the same relative path (with ``.kept`` added when the new output
    has a file of that name). Returns the relative paths kept."""
    (partial / PARTIAL_MARKER).unlink(missing_ok=True)
    if not out.exists() and not out.is_symlink():
        os.replace(partial, out)
        return []
    old = out.parent / f".{out.name}.old-{os.getpid()}"
    os.replace(out, old)
    os.replace(partial, out)
    kept = []
    for path in sorted(old.rglob("*")):
        relative = path.relative_to(old)
        if path.is_dir() and not path.is_symlink() or written_by_simrig(relative):
            continue
        target = out / relative
        if target.exists() or target.is_symlink():
            target = target.with_name(target.name + ".kept")
        target.parent.mkdir(parents=True, exist_ok=True)
        os.replace(path, target)
        kept.append(target.relative_to(out))
    shutil.rmtree(old, ignore_errors=True)
    return kept


def _pid_alive(pid: int) -> bool:
    """Whether process ``pid`` still runs. A zombie does not: a killed worker whose parent was killed too waits
    to be reaped by an init that may never do so (in a container), and ``kill(pid, 0)`` still finds it."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as stat:
            return stat.read().rpartition(")")[2].split()[0] != "Z"
    except (OSError, IndexError):
        return True  # no /proc (not Linux): the process exists



def remove_stale_partials(out: Path) -> None:
    """Remove ``out``'s partial folders left by processes that no longer run (a hard kill leaves them)."""
    for stale in out.parent.glob(f".{out.name}.partial-*"):
        pid = stale.name.rsplit("-", 1)[-1]
        if stale.is_symlink() or not (stale / PARTIAL_MARKER).is_file():
            continue  # not a folder simrig made: a user's, whatever its name
        if not pid.isdigit() or int(pid) == os.getpid() or not _pid_alive(int(pid)):
            shutil.rmtree(stale, ignore_errors=True)


def write_table_atomic(table: pa.Table, path: Path) -> None:
    """Parquet through a temporary sibling, flushed, then renamed (:func:`atomic_file`): the one way a table is
    written outside a dataset (a bench's results, a collection's index, a search's evaluations)."""
    import pyarrow.parquet as pq  # here: importing this module (every command's output checks) loads no Arrow

    with atomic_file(path) as temporary:
        pq.write_table(table, temporary)
