"""Collisions from geometry: two road users collide when their footprints touch or overlap at the end of a
simulation step.

A footprint is the ``LENGTH × WIDTH`` rectangle at a vehicle's position and heading — the rectangle of its
ground-truth box seen from above, and the polygon highway-env checks (``RoadObject.polygon``). The test is
shapely's ``intersects`` over an STRtree of the footprints (one vectorised query for all pairs; touching counts,
as it does in highway-env's separating-axis test). Anyone can repeat it on a dataset's recorded boxes.

highway-env flags a crash a step *before* the footprints meet when they would meet within the step at constant
velocity, and then pushes the pair apart, so its flag and the recorded boxes disagree. simrig's vehicles ask for
the overlap itself (:meth:`~simrig.world.vehicles.SimrigVehicle.handle_collisions`), and :class:`CollisionWatch`
records, per step, both verdicts side by side: the geometric one decides; a step where highway-env's flag says
otherwise is recorded too (``highway_env`` true, ``geometry`` false or the reverse) and the tests fail on it.

What follows a collision is the world's rule (:mod:`simrig.world.traffic`): the ego and whatever it touched stand
still where they met; two other vehicles leave the road at that frame.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..types import EGO_ID, OBSTACLE_ID, Collision


def footprints(centres: np.ndarray, headings: np.ndarray, lengths: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Shapely polygons of the rectangles ``lengths × widths`` [m] centred at ``centres`` ``(N, 2)`` [m], rotated by
    ``headings`` ``(N,)`` [rad] (any one right- or left-handed frame: overlap does not depend on it).

    >>> square = footprints(np.zeros((1, 2)), np.zeros(1), np.array([2.0]), np.array([2.0]))[0]
    >>> round(square.area, 9), square.bounds
    (4.0, (-1.0, -1.0, 1.0, 1.0))
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 2)
    half = np.stack([np.asarray(lengths, float) / 2.0, np.asarray(widths, float) / 2.0], axis=1)[:, None, :]
    signs = np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, 1.0], [1.0, -1.0]])  # corner order of RoadObject.polygon
    local = signs[None, :, :] * half  # (N, 4, 2)
    cos, sin = np.cos(headings)[:, None], np.sin(headings)[:, None]
    corners = np.stack([cos * local[..., 0] - sin * local[..., 1], sin * local[..., 0] + cos * local[..., 1]], -1)
    return shapely.polygons(corners + centres[:, None, :])


def touching_pairs(centres: np.ndarray, headings: np.ndarray, lengths: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """``(P, 2)`` index pairs ``i < j`` whose footprints (:func:`footprints`) touch or overlap, sorted.

    >>> centres = np.array([[0.0, 0.0], [4.0, 0.0], [9.0, 0.0]])
    >>> touching_pairs(centres, np.zeros(3), np.full(3, 4.0), np.full(3, 2.0)).tolist()  # 0 and 1 touch
    [[0, 1]]
    """
    polygons = footprints(centres, headings, lengths, widths)
    left, right = shapely.STRtree(polygons).query(polygons, predicate="intersects")
    keep = left < right
    pairs = np.stack([left[keep], right[keep]], axis=1).astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def closing_speeds(centres: np.ndarray, headings: np.ndarray, lengths: np.ndarray, widths: np.ndarray,
                   velocities: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """[m/s] per touching pair ``(i, j)``: how fast the two close along their contact normal — the axis, among the
    four sides' normals, on which their footprints overlap least (the separating-axis test's axis of least
    penetration); positive: closing. A rear-end gives the speed difference, a side contact the lateral speed of
    the vehicle moving across. All ``(N, ...)`` arrays in one frame.

    >>> centres = np.array([[0.0, 0.0], [4.5, 0.5]])  # b's rear overlaps a's front by 0.1 m
    >>> closing_speeds(centres, np.zeros(2), np.full(2, 4.6), np.full(2, 1.9), np.array([[20.0, 0.0], [12.0, 1.0]]),
    ...                np.array([[0, 1]])).round(6).tolist()
    [8.0]
    """
    a, b = pairs[:, 0], pairs[:, 1]
    cos, sin = np.cos(headings), np.sin(headings)
    axes = np.stack([np.stack([cos[a], sin[a]], -1), np.stack([-sin[a], cos[a]], -1),
                     np.stack([cos[b], sin[b]], -1), np.stack([-sin[b], cos[b]], -1)], axis=1)  # (P, 4, 2)

    def extent(index: np.ndarray) -> np.ndarray:
        """Half the footprint's extent along each axis (P, 4): the support of a rectangle."""
        own = np.stack([np.stack([cos[index], sin[index]], -1), np.stack([-sin[index], cos[index]], -1)], axis=1)
        dots = np.abs(np.einsum("pkd,pmd->pkm", axes, own))  # (P, 4 axes, 2 own directions)
        return dots[..., 0] * lengths[index, None] / 2.0 + dots[..., 1] * widths[index, None] / 2.0

    offset = np.einsum("pkd,pd->pk", axes, centres[b] - centres[a])  # centre distance along each axis
    overlap = extent(a) + extent(b) - np.abs(offset)
    least = np.argmin(overlap, axis=1)
    rows = np.arange(len(pairs))
    normal = axes[rows, least] * np.where(offset[rows, least] < 0.0, -1.0, 1.0)[:, None]  # from a towards b
    return ((velocities[a] - velocities[b]) * normal).sum(axis=1)


def _ident(thing, ego) -> int:
    if thing is ego:
        return EGO_ID
    return int(getattr(thing, "simrig_id", OBSTACLE_ID))


class CollisionWatch:
    """Watches one road, step by step (:meth:`after_step`), and keeps the collisions of the current frame.

    A pair is recorded once, at the step its footprints first touch; a pair that stays in contact (the ego and what
    it hit stand still together) is not recorded again. Obstacles (highway-env's ``Obstacle``, the end of a ramp's
    acceleration lane) take part with id :data:`~simrig.types.OBSTACLE_ID`."""

    def __init__(self, ego):
        self.ego = ego
        self.frame_collisions: list[Collision] = []
        self._recorded: set[tuple[int, int]] = set()
        self._crashed_before: set[int] = set()

    def before_step(self, road) -> None:
        """Remember which road users highway-env had flagged crashed before the step."""
        self._crashed_before = {id(thing) for thing in self._users(road) if thing.crashed}

    def after_step(self, road) -> list[Collision]:
        """Record the collisions this step made (both verdicts, module docstring) and return the new ones."""
        users = self._users(road)
        if len(users) < 2:
            return []
        centres = np.array([thing.position for thing in users], dtype=float)
        shape = (np.array([thing.heading for thing in users], dtype=float),
                 np.array([thing.LENGTH for thing in users], dtype=float),
                 np.array([thing.WIDTH for thing in users], dtype=float))
        pairs = touching_pairs(centres, *shape)
        velocities = np.array([getattr(thing, "velocity", np.zeros(2)) for thing in users], dtype=float)
        speeds = closing_speeds(centres, *shape, velocities, pairs)
        newly_flagged = {id(thing) for thing in users if thing.crashed} - self._crashed_before
        explained: set[int] = set()
        new = []
        for (i, j), speed in zip(pairs.tolist(), speeds.tolist(), strict=True):
            a, b = users[i], users[j]
            key = tuple(sorted((_ident(a, self.ego), _ident(b, self.ego))))
            if key in self._recorded or (key[0] == OBSTACLE_ID and key[1] == OBSTACLE_ID):
                continue
            self._recorded.add(key)
            explained |= {id(a), id(b)}
            new.append(Collision(key[0], key[1], float(speed), geometry=True,
                                 highway_env=bool(a.crashed and b.crashed)))
        for thing in users:  # highway-env's flag without touching footprints: recorded, so the tests see it
            if id(thing) in newly_flagged and id(thing) not in explained:
                new.append(Collision(_ident(thing, self.ego), _ident(thing, self.ego), 0.0, geometry=False,
                                     highway_env=True))
        self.frame_collisions.extend(new)
        return new

    def take_frame(self) -> tuple[Collision, ...]:
        """The collisions recorded since the last call, sorted by (first, second)."""
        found = tuple(sorted(self.frame_collisions, key=lambda c: (c.first, c.second)))
        self.frame_collisions = []
        return found

    @staticmethod
    def _users(road) -> list:
        objects = [thing for thing in road.objects if thing.collidable and thing.solid]
        return [*road.vehicles, *objects]
