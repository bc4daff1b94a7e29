"""simrig: a test bench for multi-camera multi-object trackers on moving vehicles.

One import gives what a script needs, loaded on first use (``import simrig`` itself imports nothing heavy)::

    import simrig

    dataset = simrig.generate("highway_surround6", seed=0, frames=40, out="runs/demo")
    run = simrig.track(dataset, "saga")                 # or your own tracker class / object
    report = simrig.score(dataset, run)
    print(report.metrics3d["overall"]["AMOTA"], report.metrics2d["overall"]["HOTA"])

Steps: :func:`load_scenario`, :func:`generate`, :func:`open_dataset`, :func:`track`, :func:`score`,
:func:`run` (all four in one call, as ``simrig run``) and :func:`bench` (a suite, as ``simrig bench``).

Records a tracker works with (:mod:`simrig.types`; frames and units are documented there):
:class:`SensorFrame` (what a tracker sees at one time step: detections as :class:`DetectionArrays`, and as
:class:`Detection` objects on request), :class:`Track` (what it returns), :class:`Box2D`, :class:`Box3D`,
:class:`EgoPose`, :class:`Camera`, :class:`Rig`, :class:`ActorClass`. The :class:`Tracker` protocol
(``reset(*, rig, seed=None)``, ``step(frame) -> list[Track]``), :func:`register` (a tracker by name), and
:class:`PerCameraTracking`, which makes a rig-level tracker of any single-camera 2D tracker.
"""

import importlib as _importlib
import typing as _typing

from simrig.version import __version__

_EXPORTS = {
    # the steps
    "load_scenario": "simrig.api",
    "generate": "simrig.api",
    "open_dataset": "simrig.api",
    "track": "simrig.api",
    "score": "simrig.api",
    "run": "simrig.api",
    "bench": "simrig.api",
    # records
    "ActorClass": "simrig.types",
    "Box2D": "simrig.types",
    "Box3D": "simrig.types",
    "Camera": "simrig.types",
    "Detection": "simrig.types",
    "DetectionArrays": "simrig.types",
    "EgoPose": "simrig.types",
    "Rig": "simrig.types",
    "SensorFrame": "simrig.types",
    "Track": "simrig.types",
    # writing a tracker
    "Tracker": "simrig.trackers.protocol",
    "register": "simrig.trackers.registry",
    "PerCameraTracking": "simrig.trackers.camera_tracking",
    "CameraTracker": "simrig.trackers.camera_tracking",
    "LocalTrack": "simrig.trackers.camera_tracking",
    # errors
    "SimrigError": "simrig.errors",
}

__all__ = [
    "ActorClass", "Box2D", "Box3D", "Camera", "CameraTracker", "Detection", "DetectionArrays", "EgoPose",
    "LocalTrack", "PerCameraTracking", "Rig", "SensorFrame", "SimrigError", "Track", "Tracker", "__version__",
    "bench", "generate", "load_scenario", "open_dataset", "register", "run", "score", "track",
]


def __getattr__(name: str):
    """Load an exported name on first use (PEP 562), so that ``import simrig`` stays cheap."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'simrig' has no attribute {name!r}")
    value = getattr(_importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """What ``dir(simrig)`` and completion show: the public names (:data:`__all__`)."""
    return sorted(__all__)


if _typing.TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from simrig.api import bench, generate, load_scenario, open_dataset, run, score, track
    from simrig.errors import SimrigError
    from simrig.trackers.camera_tracking import CameraTracker, LocalTrack, PerCameraTracking
    from simrig.trackers.protocol import Tracker
    from simrig.trackers.registry import register
    from simrig.types import (
        ActorClass,
        Box2D,
        Box3D,
        Camera,
        Detection,
        DetectionArrays,
        EgoPose,
        Rig,
        SensorFrame,
        Track,
    )

globals().pop("version", None)  # the submodule simrig.version, bound by the import above: __version__ is the name
