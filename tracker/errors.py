"""Errors a tracker raises on bad input: one line naming the frame, camera and detection."""

from __future__ import annotations


class TrackerInputError(ValueError):
    """A :class:`~simrig.types.SensorFrame` a tracker cannot use (a NaN in a box, a detection without the
    3D box a 3D tracker needs, time going backwards). The message names the frame, camera and field."""
