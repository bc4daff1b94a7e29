"""Systems under test: the ``Tracker`` protocol, the registry by name, and the reference trackers.

Trackers import only :mod:`simrig.types` (the shared records), never the world, renderer or scorer.

Registered here: ``saga`` (SAGA-Track with FOTA), ``global_hungarian`` (AB3DMOT-style pooled one-to-one),
``percam_merge`` (per-camera trackers + heuristic merging), ``simpletrack`` (3D GIoU, two-stage), ``mutr3d``
(3D tracks projected into every camera, associated there), ``polymot`` (the modern filter baseline:
category-specific motion, multi-cue cost, two-stage association), the 2D per-camera trackers ``sort``,
``deepsort``, ``bytetrack`` and ``botsort`` (BoT-SORT-style: IoU and appearance fused, ego-motion
compensation), and ``collabmot`` (stereo collaboration on top of them).
"""

from .botsort import botsort
from .bytetrack import bytetrack
from .collabmot import collabmot
from .deepsort import deepsort
from .errors import TrackerInputError
from .global_hungarian import global_hungarian
from .mutr3d import mutr3d
from .percam_merge import percam_merge
from .polymot import polymot
from .protocol import Tracker
from .registry import available, create, parameters, register
from .saga import saga
from .simpletrack import simpletrack
from .sort import sort

for _name, _factory in (
    ("saga", saga),
    ("global_hungarian", global_hungarian),
    ("percam_merge", percam_merge),
    ("simpletrack", simpletrack),
    ("sort", sort),
    ("deepsort", deepsort),
    ("collabmot", collabmot),
    ("mutr3d", mutr3d),
    ("polymot", polymot),
    ("bytetrack", bytetrack),
    ("botsort", botsort),
):
    register(_name, _factory)

__all__ = ["Tracker", "TrackerInputError", "available", "create", "parameters", "register"]
