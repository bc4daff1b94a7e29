"""Road markings as data: world-frame polylines of highway-env's painted lines.

Produced by :mod:`simrig.world` (stored in the dataset as ``road.json``), drawn by the renderer, the camera
mosaic and the bird's-eye plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DASH_LENGTH_M, DASH_PERIOD_M = 3.0, 12.0
"""[m] a striped line is painted for 3 m out of every 12 m."""


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
