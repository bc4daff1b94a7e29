"""Vehicle shapes: each actor class as two boxes (a body and a cabin, a cab and a cargo box, ...).

The same parts are used twice: as the triangle meshes pyrender draws (:mod:`simrig.render.scene`) and as
the convex solids whose silhouettes are rasterised analytically (:mod:`simrig.render.silhouette`), so the
rendered visible pixels and the unoccluded silhouette describe exactly the same object. Every part lies
inside the actor's 3D ground-truth box.

Parts are given as fractions of the actor's box: ``x_lo, x_hi`` along the length (−0.5 rear … 0.5 front),
``half_width`` as a fraction of the width, ``z_lo, z_hi`` as fractions of the height above the road.
"""

from __future__ import annotations

import numpy as np

from ..types import ActorClass

PART_FRACTIONS: dict[ActorClass, np.ndarray] = {
    # x_lo, x_hi, width fraction, z_lo, z_hi
    ActorClass.CAR: np.array([[-0.50, 0.50, 1.00, 0.00, 0.55], [-0.32, 0.18, 0.88, 0.55, 1.00]]),  # body, cabin
    ActorClass.TRUCK: np.array([[0.28, 0.50, 1.00, 0.00, 0.80], [-0.50, 0.26, 1.00, 0.00, 1.00]]),  # cab, cargo
    ActorClass.BUS: np.array([[-0.42, 0.42, 0.92, 0.00, 0.12], [-0.50, 0.50, 1.00, 0.12, 1.00]]),  # axles, body
    ActorClass.MOTORCYCLE: np.array([[-0.50, 0.50, 1.00, 0.00, 0.50], [-0.25, 0.10, 0.70, 0.50, 1.00]]),  # bike, rider
    ActorClass.PEDESTRIAN: np.array([[-0.30, 0.30, 0.60, 0.00, 0.50], [-0.50, 0.50, 1.00, 0.50, 1.00]]),  # legs, torso
    ActorClass.BICYCLE: np.array([[-0.50, 0.50, 1.00, 0.00, 0.45], [-0.20, 0.10, 0.70, 0.45, 1.00]]),  # bike, rider
}
PARTS_PER_ACTOR = 2


def unit_parts(actor_class: ActorClass | str) -> np.ndarray:
    """``(2, 6)`` parts of a class in a unit box centred at the origin: centre (x, y, z) and size (l, w, h).

    >>> unit_parts("car")[0].round(3).tolist()
    [0.0, 0.0, -0.225, 1.0, 1.0, 0.55]
    """
    fractions = PART_FRACTIONS[ActorClass(actor_class)]
    x_lo, x_hi, width, z_lo, z_hi = fractions.T
    centre = np.stack([(x_lo + x_hi) / 2.0, np.zeros_like(x_lo), (z_lo + z_hi) / 2.0 - 0.5], axis=1)
    size = np.stack([x_hi - x_lo, width, z_hi - z_lo], axis=1)
    return np.concatenate([centre, size], axis=1)


_UNIT_PARTS = np.stack([unit_parts(actor_class) for actor_class in ActorClass])  # (classes, 2, 6)
_CLASS_ROW = {actor_class.value: row for row, actor_class in enumerate(ActorClass)}


def part_boxes(boxes: np.ndarray, classes: np.ndarray) -> np.ndarray:
    """World-frame boxes of every actor's parts: ``(N, 2, 7)`` (x, y, z, length, width, height, yaw).

    boxes: ``(N, ≥7)`` world-frame actor boxes (:data:`~simrig.types.BOX3D_FIELDS` order, centre [m], size [m],
    yaw [rad]); classes: ``(N,)`` class names.
    """
    boxes = np.asarray(boxes, dtype=float)
    rows = np.array([_CLASS_ROW[str(name)] for name in classes], dtype=int)
    unit = _UNIT_PARTS[rows] if len(rows) else np.zeros((0, PARTS_PER_ACTOR, 6))
    size = boxes[:, None, 3:6]
    local = unit[..., :3] * size  # part centre in the actor's frame [m]
    cos, sin = np.cos(boxes[:, None, 6]), np.sin(boxes[:, None, 6])
    out = np.empty((len(boxes), PARTS_PER_ACTOR, 7))
    out[..., 0] = boxes[:, None, 0] + cos * local[..., 0] - sin * local[..., 1]
    out[..., 1] = boxes[:, None, 1] + sin * local[..., 0] + cos * local[..., 1]
    out[..., 2] = boxes[:, None, 2] + local[..., 2]
    out[..., 3:6] = unit[..., 3:6] * size
    out[..., 6] = boxes[:, None, 6]
    return out
