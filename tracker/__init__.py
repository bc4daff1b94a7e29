"""Systems under test: the ``Tracker`` protocol, the registry by name, and the reference trackers.

Trackers import only :mod:`simrig.types` (the shared records), never the world, renderer or scorer.

Registered here: ``saga`` (SAGA-Track with FOTA), ``global_hungarian`` (AB3DMOT-style pooled one-to-one),
``percam_merge`` (per-camera trackers + heuristic merging), ``simpletrack`` (3D GIoU, two-stage), ``mutr3d``
(3D tracks projected into every camera, associated there), ``polymot`` (the modern filter baseline:
category-specific motion, multi-cue cost, two-stage association), the 2D per-camera trackers ``sort``,
``deepsort``, ``bytetrack`` and ``botsort`` (BoT-SORT-style: IoU and appearance fused, ego-motion
compensation), ``collabmot`` (stereo collaboration on top of them), ``learned`` (the Kalman tracker with a
learned association in place of the Mahalanobis gate, trained on simrig data), and ``degraded`` (another tracker
with late, relabelled or velocity-noisy output, for studies of what errors cost).
"""

from .errors import TrackerInputError
from .protocol import Tracker
from .registry import available, create, parameters, register, register_lazily

REFERENCE_FACTORIES = {
    name: f"{__name__}.{module}:{name}" for name, module in (
        ("saga", "saga"), ("global_hungarian", "global_hungarian"), ("percam_merge", "percam_merge"),
        ("simpletrack", "simpletrack"), ("sort", "sort"), ("deepsort", "deepsort"), ("collabmot", "collabmot"),
        ("mutr3d", "mutr3d"), ("polymot", "polymot"), ("bytetrack", "bytetrack"), ("botsort", "botsort"),
        ("learned", "learned"), ("degraded", "degraded"),
    )
}
"""Name → ``module:factory`` of every tracker simrig registers; each module is imported when its tracker is first
asked for, so a ``saga`` run imports no other tracker (nor what they need: ``scipy.stats``, the learned model)."""
for _name, _reference in REFERENCE_FACTORIES.items():
    register_lazily(_name, _reference)

TRAINED_ON_SIMRIG = ("learned",)
"""Registered trackers whose model was trained on simrig data: not reference trackers (the papers' methods and the
Kalman baselines, every one in the ``standard`` suite) but compared with them in the ``learned`` suite, on the road
types they were trained on and on one held out."""
DEGRADERS = ("degraded",)
"""Registered trackers that make another tracker worse on purpose (studies of what errors cost, e.g. the
``metric_validity`` suite): not reference trackers either."""

__all__ = ["DEGRADERS", "TRAINED_ON_SIMRIG", "Tracker", "TrackerInputError", "available", "create", "parameters",
           "register"]
