"""scipy's Hungarian solver (``linear_sum_assignment``) without importing all of ``scipy.optimize``.

``from scipy.optimize import linear_sum_assignment`` runs ``scipy.optimize``'s ``__init__``, which imports the
whole package (the optimisers, ``scipy.linalg``, ``scipy.sparse``, ``scipy.fft``): about 0.3 s of a fresh
process (measured with ``python -X importtime``, scipy 1.17), most of what a first ``simrig score`` would spend
before scoring. The solver itself is the compiled module ``scipy.optimize._lsap``; this module loads that file
alone, on the first call, and uses the same function. Should scipy ever lay it out otherwise, it falls back to
the public import: the same solver either way, only the start-up time differs.
"""

from __future__ import annotations

import functools
import importlib.machinery
import importlib.util
from pathlib import Path

import numpy as np


@functools.cache
def _solver():
    """scipy's compiled ``linear_sum_assignment``, loaded from ``scipy/optimize/_lsap*`` without the package."""
    try:
        package = importlib.util.find_spec("scipy.optimize")  # finds the folder; runs no __init__ of it
        for folder in package.submodule_search_locations or ():
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = Path(folder) / f"_lsap{suffix}"
                if path.is_file():
                    loader = importlib.machinery.ExtensionFileLoader("scipy.optimize._lsap", str(path))
                    spec = importlib.util.spec_from_file_location("scipy.optimize._lsap", path, loader=loader)
                    module = importlib.util.module_from_spec(spec)
                    loader.exec_module(module)
                    return module.linear_sum_assignment
    except (ImportError, AttributeError, OSError):
        pass
    from scipy.optimize import linear_sum_assignment

    return linear_sum_assignment


def linear_sum_assignment(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a minimum-cost assignment of ``cost`` ``(n, m)``: scipy's solver, as
    ``scipy.optimize.linear_sum_assignment`` (same function, same ties).

    >>> linear_sum_assignment(np.array([[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]]))
    (array([0, 1, 2]), array([1, 0, 2]))
    """
    return _solver()(cost)
