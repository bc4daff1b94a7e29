"""Systems under test: the ``Tracker`` protocol and the registry by name.

Trackers import only :mod:`simrig.types` (the shared records), never the world, renderer or scorer.
"""

from .protocol import Tracker
from .registry import available, create, register

__all__ = ["Tracker", "available", "create", "register"]
