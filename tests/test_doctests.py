"""Doctests of the packages whose source folders are not named after their import names.

``tracker/`` installs as ``simrig.trackers`` and ``scenarios/`` as ``simrig.scenarios`` (pyproject's
package-dir mapping), so pytest's ``--doctest-modules`` cannot collect them by path without importing a
second, top-level copy. They are run here through their installed names instead.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest
import simrig.scenarios
import simrig.trackers


def _modules(package) -> list[str]:
    names = [package.__name__]
    names += [info.name for info in pkgutil.walk_packages(package.__path__, package.__name__ + ".")]
    return sorted(names)


@pytest.mark.parametrize("name", _modules(simrig.trackers) + _modules(simrig.scenarios))
def test_doctests(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} of {result.attempted} doctests failed in {name}"
