"""Why a detection was missed, degraded or false: causes as bit flags, stored as lists of names.

A (frame, actor, camera) row may carry several causes (an actor both far and occluded); a miss with no
cause at all was a plain random miss of the detector (``p_max`` < 1).
"""

from __future__ import annotations

import enum

import numpy as np


class Cause(enum.IntFlag):
    """What affected a detection or a miss. ``names`` are the strings stored in the dataset."""

    OUT_OF_VIEW = enum.auto()
    """Not inside the camera's image (or behind it)."""
    TRUNCATED = enum.auto()
    """Cut by the image border enough to lower the detection probability."""
    OCCLUDED = enum.auto()
    """Hidden behind other actors enough to lower the detection probability (or a scheduled occlusion)."""
    FAR = enum.auto()
    """Beyond the detector's full range."""
    SCHEDULED_OCCLUSION = enum.auto()
    """An ``occlude`` perturbation hid it."""
    SCHEDULED_MISS = enum.auto()
    """A ``miss_burst`` perturbation was active for it."""
    BLACKOUT = enum.auto()
    """Its camera was blacked out."""
    DROPPED_FRAME = enum.auto()
    """The whole sensor frame was dropped."""
    CALIBRATION = enum.auto()
    """Its 3D estimate was lifted with a wrong calibration."""
    NOISE = enum.auto()
    """Its noise was scaled up by a ``noise`` perturbation."""
    CLUTTER = enum.auto()
    """A false positive: no actor behind it."""
    BURST = enum.auto()
    """The detector's miss process was in its bad state (a Gilbert–Elliott miss burst)."""
    GHOST = enum.auto()
    """A false positive from a ghost object with a life of its own (static, or shadowing a vehicle)."""
    DUPLICATE = enum.auto()
    """A false positive: a second box on an object already detected in the same camera (failed NMS)."""
    CONFUSED = enum.auto()
    """Detected, but reported with another class (class confusion)."""


CAUSE_NAMES: tuple[str, ...] = tuple(cause.name.lower() for cause in Cause)
"""Stored names in bit order: ``out_of_view``, ``truncated``, ``occluded``, ..."""
CAUSE_BITS = np.array([int(cause) for cause in Cause], dtype=np.int64)
"""The bit of each name in :data:`CAUSE_NAMES`, in the same order."""


def cause_masks(names: list[list[str]]) -> np.ndarray:
    """Inverse of :func:`simrig.pipeline.frame_columns.cause_lists`: ``(R,)`` bit masks from lists of cause names."""
    lookup = {name: int(bit) for name, bit in zip(CAUSE_NAMES, CAUSE_BITS, strict=True)}
    return np.array([sum(lookup[name] for name in row) for row in names], dtype=np.int64)
