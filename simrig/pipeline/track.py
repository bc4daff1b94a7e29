"""``track``: run a registered tracker over a dataset's sensor frames; its tracks in memory, and on disk when asked.

The tracker sees exactly what :meth:`~simrig.dataset.Dataset.sensor_frames` yields (no ground truth);
the bench and the CLI both come through here, so a user's tracker and the reference trackers are run alike.
"""

from __future__ import annotations

import inspect
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import simrig.trackers as tracker_registry
from simrig.dataset import Dataset
from simrig.dataset.outputs import check_own_folder
from simrig.dataset.tracks_file import (
    TRACKS2D_FILE,
    TRACKS3D_FILE,
    TrackSet,
    TrackTables,
    tracks_in_memory,
    write_tracks,
)
from simrig.errors import SimrigError
from simrig.interrupts import stop_if_interrupted
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S, TrackerFault, checked_tracks, time_limit
from simrig.pipeline.trust import TrackerReferenceError, import_tracker_factory, raised_at
from simrig.trackers.errors import TrackerInputError
from simrig.trackers.registry import check_param_types
from simrig.types import Track


class TrackingError(SimrigError):
    """A tracker could not be built or rejected its input; the message names the tracker and the frame."""


@dataclass(frozen=True, eq=False)
class TrackingRun:
    """A tracker's output (``tracks``, validated, ready for :func:`simrig.scoring.score`), where it was written
    (``out``, None when it was kept in memory only) and how long the tracker's ``step`` calls took in total
    [s] (reading the dataset and writing the tracks excluded)."""

    out: Path | None
    frames: int
    track_rows: int
    step_seconds: float
    tracks: TrackSet

    @property
    def frames_per_second(self) -> float:
        return self.frames / self.step_seconds if self.step_seconds > 0 else float("inf")


def build_tracker(name, params: dict | None = None):
    """A tracker from ``name``: a registered name, ``"module:attribute"`` (a factory or class to import), a
    factory or class (called with ``params``) or a tracker object (used as is). A :class:`TrackingError`
    naming the tracker and the bad name or parameter otherwise."""
    params = params or {}
    for key, value in params.items():  # nan or inf in a suite, a tracker.json or a Python call: never a setting
        if isinstance(value, float) and not math.isfinite(value):
            raise TrackingError(f"tracker {tracker_display(name)!r}: parameter {key} = {value}: a parameter must be "
                                "a finite number")
    if isinstance(name, str) and ":" in name and name not in tracker_registry.available():
        name = _import(name)
    if not isinstance(name, str):
        if isinstance(name, tracker_registry.Tracker) and not isinstance(name, type):
            if params:
                raise TrackingError(f"tracker {name!r}: parameters {sorted(params)} given for a tracker object")
            return name
        try:
            signature = inspect.signature(name)
        except (TypeError, ValueError):  # a callable without a signature: the call below judges the parameters
            signature = None
        if signature is not None:
            try:
                check_param_types(getattr(name, "__qualname__", repr(name)), signature, params)
            except ValueError as error:
                raise TrackingError(str(error)) from None
        try:
            built = name(**params)
        except TypeError as error:
            raise TrackingError(f"tracker {getattr(name, '__qualname__', name)!r}: {error}") from None
        except (Exception, SystemExit) as error:  # the tracker's own code failed while being built
            raise TrackingError(f"tracker {getattr(name, '__qualname__', name)!r}: building it raised "
                                f"{type(error).__name__}: {error}") from error
        if not isinstance(built, tracker_registry.Tracker):
            raise TrackingError(f"tracker {getattr(name, '__qualname__', name)!r} built a {type(built).__name__}, "
                                "which has no reset/step")
        return built
    try:
        return tracker_registry.create(name, **params)
    except (KeyError, ValueError, TypeError) as error:
        message = str(error.args[0] if error.args else error)
        raise TrackingError(message if repr(name) in message else f"tracker {name!r}: {message}") from None
    except (Exception, SystemExit) as error:  # a registered (entry point) tracker's own code failed
        raise TrackingError(f"tracker {name!r}: building it raised {type(error).__name__}: {error}") from error


def _import(spec: str):
    """``"package.module:Attribute.path"`` → the tracker factory; a :class:`TrackingError` naming the spec when
    it cannot be imported or is not a tracker factory (:mod:`simrig.pipeline.trust`)."""
    try:
        return import_tracker_factory(spec)
    except TrackerReferenceError as error:
        raise TrackingError(str(error)) from error.__cause__  # the module's own failure, for SIMRIG_TRACEBACK=1


def run_tracker(dataset: Dataset | Path | str, name, out: Path | str | None = None, params: dict | None = None,
                *, seed: int | None = None, frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S) -> TrackingRun:
    """Build tracker ``name`` (anything :func:`build_tracker` takes) with ``params``, ``reset`` it on the
    dataset's rig (``seed`` defaults to the dataset's), step it over every sensor frame, and keep its tracks
    (``TrackingRun.tracks``); with ``out``, also write them to that folder. A tracker with a ``finish()``
    method (semi-online) has its answer for each frame kept instead of ``step``'s.

    The tracker's code is guarded (:mod:`simrig.pipeline.guard`): each call is stopped after
    ``frame_time_limit_s`` [s] (None or 0: no limit) with a :class:`~simrig.pipeline.guard.TrackerTimeout`; an
    exception it raises or a malformed return value is a :class:`~simrig.pipeline.guard.TrackerFault` naming
    the tracker, the frame and the field."""
    if not isinstance(dataset, Dataset):
        dataset = Dataset.open(dataset)
    if out is not None:  # before any work: a tracks folder holds tracks, never a user's other files
        check_own_folder(Path(out), what="tracks folder", marker=TRACKS2D_FILE, made=(TRACKS3D_FILE, "tracker.json"))
    tracker = build_tracker(name, params)
    label = tracker_display(name)
    cameras = dataset.rig.camera_names
    with guarded_call(label, "reset()", frame_time_limit_s):
        tracker.reset(rig=dataset.rig, seed=dataset.seed if seed is None else seed)
    finish = getattr(tracker, "finish", None)
    semi_online = callable(finish)
    builder = TrackTables()
    kept: list[tuple[int, list[Track]]] = []  # a semi-online tracker's answers, until finish() revises them
    frames, rows, elapsed = 0, 0, 0.0
    for frame in dataset.sensor_frames():
        stop_if_interrupted()
        start = time.perf_counter()
        try:
            with guarded_call(label, f"frame {frame.frame}: step()", frame_time_limit_s):
                tracks = tracker.step(frame)
        except TrackerInputError as error:
            raise TrackingError(f"tracker {name!r}: {error}") from None
        elapsed += time.perf_counter() - start
        tracks = checked_tracks(tracks, tracker=label, frame=frame.frame, cameras=cameras)
        frames += 1
        if semi_online:
            kept.append((frame.frame, tracks))
        else:  # kept as a few numbers per track: memory stays small over long runs
            builder.add(frame.frame, tracks)
            rows += len(tracks)
    if semi_online:  # a semi-online tracker's final word on every frame (it may revise the past)
        start = time.perf_counter()
        limit = frame_time_limit_s * max(len(kept), 1) if frame_time_limit_s else None
        with guarded_call(label, "finish()", limit):
            revised = finish()
            revised = dict(revised)
        elapsed += time.perf_counter() - start
        for index, tracks in kept:
            if index in revised:
                tracks = checked_tracks(revised[index], tracker=label, frame=index, cameras=cameras, call="finish()")
            builder.add(index, tracks)
            rows += len(tracks)
    tables = builder.tables()
    tracks = tracks_in_memory(tables, frame_count=dataset.frame_count, cameras=cameras,
                              source=f"tracker {label!r}", made_on=dataset.identity)
    path = write_tracks(out, tables, made_on=dataset.identity) if out is not None else None
    return TrackingRun(path, frames, rows, elapsed, tracks)


@contextmanager
def guarded_call(tracker: str, call: str, seconds: float | None) -> Iterator[None]:
    """The tracker's ``call`` under a time limit; anything it raises (but its own input complaint) becomes a
    :class:`TrackerFault` naming tracker and call, with the original exception chained."""
    try:
        with time_limit(seconds, f"tracker {tracker!r}: {call}"), _no_hard_exit():
            yield
    except (TrackerFault, TrackerInputError):
        raise
    except (Exception, SystemExit) as error:  # SystemExit: the tracker called exit(), which must not end simrig
        raise TrackerFault(f"tracker {tracker!r}: {call} raised {type(error).__name__}: {error}"
                           f"{raised_at(error)}") from error


class _HardExit(Exception):
    """The tracker called ``os._exit``: raised in its place, so that simrig reports it and writes nothing partial."""

    def __init__(self, code):
        super().__init__(f"os._exit({code!r}) called, which would have ended simrig without a word")


@contextmanager
def _no_hard_exit() -> Iterator[None]:
    """``os._exit`` raises :class:`_HardExit` while a tracker's call runs (it would end the process at once, with
    no message and no clean-up: ``simrig drive`` exited 3 having said nothing)."""
    import os

    real = os._exit

    def refuse(code=0):
        raise _HardExit(code)

    os._exit = refuse
    try:
        yield
    finally:
        os._exit = real


def tracker_display(name) -> str:
    """A tracker reference as a user would name it."""
    return name if isinstance(name, str) else getattr(name, "__qualname__", type(name).__name__)


def tracker_reference(tracker) -> str | None:
    """A string that names ``tracker`` on a command line (``simrig run``, ``simrig replay``): itself if a
    string, else ``module:qualname`` of a class or function (``None`` when it has none, e.g. a lambda or an
    instance of a local class)."""
    if isinstance(tracker, str):
        return tracker
    target = tracker if callable(tracker) and hasattr(tracker, "__qualname__") else type(tracker)
    qualname, module = getattr(target, "__qualname__", ""), getattr(target, "__module__", "")
    if not module or "<" in qualname:
        return None
    return f"{module}:{qualname}"
