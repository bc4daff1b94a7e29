"""Why a detection was missed, degraded or false: causes as bit flags, stored as lists of names.

A (frame, actor, camera) row may carry several causes (an actor both far and occluded); a miss with no
cause at all was a plain random miss of the detector (``p_max`` < 1).
"""

from __future__ import annotations

import enum

import numpy as np
import pyarrow as pa


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


CAUSE_NAMES: tuple[str, ...] = tuple(cause.name.lower() for cause in Cause)
"""Stored names in bit order: ``out_of_view``, ``truncated``, ``occluded``, ..."""
_BITS = np.array([int(cause) for cause in Cause], dtype=np.int64)


def cause_lists(masks: np.ndarray) -> pa.ListArray:
    """A list<string> column from ``(R,)`` int64 bit masks, names in :data:`CAUSE_NAMES` order.

    >>> cause_lists(np.array([0, int(Cause.FAR | Cause.OCCLUDED)])).to_pylist()
    [[], ['occluded', 'far']]
    """
    bits = (np.asarray(masks, dtype=np.int64)[:, None] & _BITS[None, :]) != 0
    rows, which = np.nonzero(bits)
    offsets = np.concatenate([[0], np.cumsum(bits.sum(axis=1))]).astype(np.int32)
    names = pa.array(np.array(CAUSE_NAMES, dtype=object)[which].tolist(), type=pa.string())
    return pa.ListArray.from_arrays(pa.array(offsets), names)


def cause_masks(names: list[list[str]]) -> np.ndarray:
    """Inverse of :func:`cause_lists`: ``(R,)`` bit masks from lists of cause names."""
    lookup = {name: int(bit) for name, bit in zip(CAUSE_NAMES, _BITS, strict=True)}
    return np.array([sum(lookup[name] for name in row) for row in names], dtype=np.int64)
