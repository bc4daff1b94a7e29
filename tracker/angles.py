"""Angle helpers [rad], vectorised."""

from __future__ import annotations

import numpy as np


def wrap(angle):
    """``angle`` wrapped to [−π, π).

    >>> float(wrap(3 * np.pi / 2))
    -1.5707963267948966
    """
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def heading_difference(a, b):
    """``a − b`` with the heading ambiguity removed (AB3DMOT's orientation correction): wrapped to
    [−π, π), then folded by ±π into [−π/2, π/2], since a box facing backwards is the same box.

    >>> round(float(heading_difference(np.pi, 0.1)), 6)
    -0.1
    """
    d = wrap(np.asarray(a) - np.asarray(b))
    return np.where(d > np.pi / 2, d - np.pi, np.where(d < -np.pi / 2, d + np.pi, d))
