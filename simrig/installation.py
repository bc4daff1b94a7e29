"""Which installed distributions hold files of the ``simrig`` package (records layer: standard library only).

simrig installs as the distribution ``simrig-mot``; PyPI's ``simrig`` is an unrelated project whose files land in
the same ``simrig/`` folder. A tracker plugin that declares ``dependencies = ["simrig"]`` pulls it in, and it
overwrites simrig's own files without a word from pip. :func:`ownership_warning` notices: ``simrig --version``,
``simrig trackers`` and the pytest plugin's header print it.
"""

from __future__ import annotations

import re
from importlib import metadata

from .version import DISTRIBUTION


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def other_owners() -> list[str]:
    """``NAME VERSION`` of every installed distribution other than simrig's own that lists files under
    ``simrig/`` in its record, sorted."""
    owners = set()
    for distribution in metadata.distributions():
        name = distribution.metadata.get("Name") or ""
        if _canonical(name) == _canonical(DISTRIBUTION):
            continue
        if _owns_simrig_files(distribution):
            owners.add(f"{name} {distribution.version}")
    return sorted(owners)


def _owns_simrig_files(distribution: metadata.Distribution) -> bool:
    """Whether ``distribution``'s record lists a file under ``simrig/``: its RECORD searched as text (building a
    path object per recorded file, as ``Distribution.files`` does, took 0.4 s over a large environment), its
    ``files`` when it has no RECORD (an egg-info install)."""
    record = distribution.read_text("RECORD")
    if record is not None:
        return _RECORDED.search(record.replace("\\", "/")) is not None
    return any(str(path).replace("\\", "/").startswith("simrig/") for path in distribution.files or ())


_RECORDED = re.compile(r'^"?simrig/', re.MULTILINE)
"""A RECORD line (CSV: path, hash, size) of a file under ``simrig/``; a path with a comma is quoted."""


def ownership_warning() -> str | None:
    """One line when another distribution owns files of the ``simrig`` package (module docstring); None when
    none does."""
    owners = other_owners()
    if not owners:
        return None
    return (f"simrig: warning: {', '.join(owners)} also installed files into the simrig package, over simrig's own "
            f"(PyPI's 'simrig' is another project): pip uninstall {owners[0].split()[0]} && pip install "
            f"--force-reinstall {DISTRIBUTION}; a tracker plugin depends on '{DISTRIBUTION}', not 'simrig'")
