"""The ``Tracker`` protocol, Gymnasium-like: ``reset`` once per sequence, ``step`` once per frame."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from simrig.types import Rig, SensorFrame, Track


@runtime_checkable
class Tracker(Protocol):
    """A multi-object tracker.

    ``reset(*, rig, seed=None)`` starts a new sequence seen by ``rig`` (seed any internal randomness from
    ``seed``); ``step(frame)`` consumes one :class:`~simrig.types.SensorFrame` and returns the tracks alive
    at that frame.

    Optional: ``finish()``, called after the last frame, returns ``[(frame, tracks), …]`` — a semi-online
    tracker's final output for the frames it stepped, which replaces what ``step`` returned for them (e.g.
    CollabMOT's interpolated boxes and corrected ids). An online tracker does not define it.
    """

    def reset(self, *, rig: Rig, seed: int | None = None) -> None: ...

    def step(self, frame: SensorFrame) -> list[Track]: ...
