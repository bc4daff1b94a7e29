"""The painted lines of a highway-env road network, in the world frame, painted only where lanes are.

highway-env gives each lane a line type per side (continuous, striped, none) and draws it over the lane's whole
length, so a road's edge line runs straight across the mouth of an exit lane that leaves it, and the lines of two
crossing roads run through each other's junction box. Here a painted line is kept only where it does not pass
through the inside of a lane: the part of a line lying more than :data:`MARGIN_M` inside any lane's strip (its
centreline ± half its width, offset as highway-env offsets it) is left out, so a line on the border of two lanes
stays and a line across a lane another vehicle drives on does not. The strips are shapely polygons between the
lane's two sampled borders, each moved :data:`MARGIN_M` in.
"""

from __future__ import annotations

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from shapely import LineString, MultiLineString, Polygon, line_merge, unary_union

from simrig.road import RoadMarkings

SAMPLE_M = 2.0
"""[m] spacing of the samples along a curved lane's lines (a straight one is its two ends)."""
STRIP_SAMPLE_M = 0.5
"""[m] spacing of the samples along a curved lane's strip (finer: a chord cuts into a curved border by
spacing² · curvature / 8, a few centimetres on the roundabout's entries at 2 m)."""
MARGIN_M = 0.25
"""[m] a line must lie this far inside a lane's strip to count as crossing it (a line on the border between two
lanes lies on both strips' edges; curved borders sampled every 2 m stray from each other by far less)."""
MIN_PIECE_M = 1.0
"""[m] shorter pieces left of a clipped line are dropped: the sliver between two lanes of a road a line crosses
(2 × :data:`MARGIN_M` wide) is not paint."""


def road_markings(network, centre: tuple[float, float]) -> RoadMarkings:
    """The painted lines of ``network`` (a highway-env ``RoadNetwork``), clipped to leave out what crosses a lane
    (module docstring), in the world frame (X = x, Y = −y: highway-env's y points right). ``centre`` [m]: a world
    point at the middle of the map."""
    lanes = network.lanes_list()
    lines, dashed, strips = [], [], []
    for lane in lanes:
        samples = _samples(lane, STRIP_SAMPLE_M)
        half = np.maximum(np.array([lane.width_at(s) for s in samples]) / 2.0 - MARGIN_M, 0.01)
        left = np.array([lane.position(s, -h) for s, h in zip(samples, half, strict=True)])
        right = np.array([lane.position(s, h) for s, h in zip(samples, half, strict=True)])
        strips.append(Polygon(_world(np.vstack([left, right[::-1]]))).buffer(0))  # buffer(0): a valid polygon
        samples = _samples(lane, SAMPLE_M)
        for side, line_type in zip((-0.5, 0.5), lane.line_types, strict=True):
            if line_type == LineType.NONE:
                continue
            points = np.array([lane.position(s, side * lane.width_at(s)) for s in samples])
            lines.append(_world(points))
            dashed.append(line_type == LineType.STRIPED)
    inside = unary_union(strips)
    kept_lines, kept_dashed = [], []
    for line, is_dashed in zip(lines, dashed, strict=True):
        for piece in _pieces(LineString(line).difference(inside)):
            kept_lines.append(piece)
            kept_dashed.append(is_dashed)
    return RoadMarkings(tuple(kept_lines), tuple(kept_dashed), centre=centre)


def _samples(lane, spacing: float) -> np.ndarray:
    """[m] longitudinal positions along ``lane``, ``spacing`` [m] apart at most (a straight lane: its two ends;
    highway-env's ``SineLane`` subclasses ``StraightLane`` but bends, so the test is on the exact type)."""
    if type(lane) is StraightLane:
        return np.array([0.0, lane.length])
    return np.linspace(0.0, lane.length, max(2, int(np.ceil(lane.length / spacing)) + 1))


def _world(points: np.ndarray) -> np.ndarray:
    """highway-env (x, y) → the world frame (x, −y)."""
    return np.stack([points[:, 0], -points[:, 1]], axis=1)


def _pieces(geometry) -> list[np.ndarray]:
    """The polylines ``(K, 2)`` of a shapely (multi)line, in order, each at least :data:`MIN_PIECE_M` long."""
    if geometry.is_empty:
        return []
    if isinstance(geometry, MultiLineString):
        geometry = line_merge(geometry)  # pieces the difference split at a vertex, joined again
    parts = getattr(geometry, "geoms", [geometry])
    return [np.asarray(part.coords, dtype=float) for part in parts
            if isinstance(part, LineString) and part.length >= MIN_PIECE_M]
