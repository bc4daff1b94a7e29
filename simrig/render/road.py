"""The road as colour renders show it: a grey ground plane and the lane markings of highway-env's network.

Markings arrive as world-frame polylines (:class:`RoadMarkings`, produced by :mod:`simrig.world`, stored in
the dataset as ``road.json``); :func:`painted_quads` turns them into flat quads (the scene makes one
static mesh of them).
Markings and ground are absent from segmentation renders: they never occlude a vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MARKING_WIDTH_M = 0.15
"""[m] painted line width."""
DASH_LENGTH_M, DASH_PERIOD_M = 3.0, 12.0
"""[m] a striped line is painted for 3 m out of every 12 m."""
GROUND_HALF_SIZE_M = 2000.0
"""[m] half side of the square ground plane under the whole map."""
MARKING_HEIGHT_M = 0.02
"""[m] markings float this far above the ground to avoid z-fighting."""


@dataclass(frozen=True)
class RoadMarkings:
    """Painted lines of a road map: world-frame polylines (``(K, 2)`` [m]) and whether each is dashed."""

    lines: tuple[np.ndarray, ...]
    dashed: tuple[bool, ...]
    centre: tuple[float, float] = (0.0, 0.0)
    """[m] a world point at the middle of the map (the ground plane is centred there)."""

    def to_dict(self) -> dict:
        return {
            "frame": "world: x along the road, y left [m]",
            "centre": list(self.centre),
            "lines": [{"dashed": d, "points": np.round(line, 4).tolist()} for line, d in zip(
                self.lines, self.dashed, strict=True)],
        }

    @classmethod
    def from_dict(cls, data: dict) -> RoadMarkings:
        return cls(
            lines=tuple(np.asarray(entry["points"], dtype=float).reshape(-1, 2) for entry in data["lines"]),
            dashed=tuple(bool(entry["dashed"]) for entry in data["lines"]),
            centre=tuple(data.get("centre", (0.0, 0.0))),
        )


def dash_segments(line: np.ndarray, dashed: bool) -> np.ndarray:
    """``(S, 2, 2)`` painted segments of a polyline: the whole line, or 3 m dashes every 12 m."""
    segments = np.stack([line[:-1], line[1:]], axis=1)
    if not dashed or not len(segments):
        return segments
    lengths = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    out = []
    for (a, b), s0, length in zip(segments, start, lengths, strict=True):
        if length <= 0:
            continue
        first = np.ceil(s0 / DASH_PERIOD_M) * DASH_PERIOD_M
        for s in np.arange(first, s0 + length, DASH_PERIOD_M):
            t0, t1 = (s - s0) / length, min(1.0, (s + DASH_LENGTH_M - s0) / length)
            out.append([a + t0 * (b - a), a + t1 * (b - a)])
    return np.array(out).reshape(-1, 2, 2)


def painted_quads(markings: RoadMarkings) -> np.ndarray:
    """``(Q, 4, 3)`` world-frame corners of every painted segment, a flat quad just above the road."""
    segments = [dash_segments(line, dashed) for line, dashed in zip(markings.lines, markings.dashed, strict=True)]
    segments = np.concatenate(segments) if segments else np.zeros((0, 2, 2))
    direction = segments[:, 1] - segments[:, 0]
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    keep = norm[:, 0] > 0
    segments, direction, norm = segments[keep], direction[keep], norm[keep]
    side = np.stack([-direction[:, 1], direction[:, 0]], axis=1) / norm * (MARKING_WIDTH_M / 2.0)
    quads = np.stack([segments[:, 0] - side, segments[:, 1] - side, segments[:, 1] + side, segments[:, 0] + side], 1)
    return np.concatenate([quads, np.full((*quads.shape[:2], 1), MARKING_HEIGHT_M)], axis=2)
