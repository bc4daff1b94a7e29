"""Where simrig may write: checked before any work, so a bad ``--out`` / ``--json`` costs nothing and harms nothing.

An output path is refused when it lies in a system folder (``/proc``, ``/etc``, ...), under an existing file,
inside one of the command's inputs (a dataset folder, a tracks folder) or around one of them (an output folder
that would hold, and on ``--overwrite`` delete, the input). Partial folders are named per process, so two
commands writing to the same place never share one.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterable
from pathlib import Path

from ..errors import SimrigError

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
    output is a folder (an existing file there is refused) or a file (an existing folder there is refused)."""
    path = Path(path)
    resolved = path.resolve()
    if resolved == Path(resolved.anchor):
        raise OutputPathError(f"{what} {str(path)!r} is the root of the file system")
    for system in SYSTEM_FOLDERS:
        if _inside(resolved, Path(system)):
            raise OutputPathError(f"{what} {str(path)!r} is in the system folder {system}")
    for parent in resolved.parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputPathError(f"{what} {str(path)!r} is under {str(parent)!r}, which is a file")
            break
    if resolved.exists():
        if folder and not resolved.is_dir():
            raise OutputPathError(f"{what} {str(path)!r} is a file, not a folder")
        if not folder and resolved.is_dir():
            raise OutputPathError(f"{what} {str(path)!r} is a folder, not a file")
    for source in inputs:
        if source is None:
            continue
        source_resolved = Path(source).resolve()
        if _inside(resolved, source_resolved):
            raise OutputPathError(f"{what} {str(path)!r} is inside the input {str(source)!r}; write elsewhere")
        if folder and source_resolved.is_relative_to(resolved):
            raise OutputPathError(f"{what} {str(path)!r} holds the input {str(source)!r}; write elsewhere")
    return path


def partial_sibling(out: Path) -> Path:
    """The hidden partial folder of ``out`` for this process: ``.<name>.partial-<pid>`` next to it."""
    return out.parent / f".{out.name}.partial-{os.getpid()}"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_partials(out: Path) -> None:
    """Remove ``out``'s partial folders left by processes that no longer run (a hard kill leaves them)."""
    for stale in out.parent.glob(f".{out.name}.partial-*"):
        pid = stale.name.rsplit("-", 1)[-1]
        if not pid.isdigit() or int(pid) == os.getpid() or not _pid_alive(int(pid)):
            shutil.rmtree(stale, ignore_errors=True)
