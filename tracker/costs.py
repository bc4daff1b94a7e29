"""Association costs between N predicted tracks and M detections, all vectorised over the (N, M) pairs.

Boxes are world-frame 3D boxes, rows of ``(·, ≥7)`` arrays in :data:`~simrig.types.BOX3D_FIELDS` order:
centre (x, y, z) [m], size (length, width, height) [m], yaw [rad].
"""

from __future__ import annotations

import numpy as np
import shapely

from .angles import heading_difference

_UNIT_CORNERS = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])  # counter-clockwise


def bev_corners(boxes: np.ndarray) -> np.ndarray:
    """Footprint corners (N, 4, 2) [m], counter-clockwise, of boxes (N, ≥7).

    >>> bev_corners(np.array([[1.0, 2.0, 0.0, 4.0, 2.0, 1.5, 0.0]]))[0].tolist()
    [[3.0, 3.0], [-1.0, 3.0], [-1.0, 1.0], [3.0, 1.0]]
    """
    local = _UNIT_CORNERS[None] * boxes[:, None, 3:5]
    cos, sin = np.cos(boxes[:, 6])[:, None], np.sin(boxes[:, 6])[:, None]
    x = boxes[:, None, 0] + cos * local[..., 0] - sin * local[..., 1]
    y = boxes[:, None, 1] + sin * local[..., 0] + cos * local[..., 1]
    return np.stack([x, y], axis=-1)


def bev_distance(tracks: np.ndarray, detections: np.ndarray) -> np.ndarray:
    """Distance [m] between footprint centres, (N, M).

    >>> bev_distance(np.zeros((1, 7)), np.array([[3.0, 4.0, 9, 1, 1, 1, 0]])).tolist()
    [[5.0]]
    """
    return np.hypot(tracks[:, None, 0] - detections[None, :, 0], tracks[:, None, 1] - detections[None, :, 1])


def mahalanobis(predicted: np.ndarray, innovation: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Eq. 4 of SAGA-Track: √((z − ẑ)ᵀ S⁻¹ (z − ẑ)) for every (track, detection) pair, (N, M).

    predicted: (N, 7) predicted measurements ẑ = H x̂ [x, y, z, l, w, h, θ]; innovation: (N, 7, 7)
    innovation covariances S; measured: (M, ≥7) detections z. The heading difference is folded into
    [−π/2, π/2] (a box facing backwards is the same box).
    """
    diff = measured[None, :, :7] - predicted[:, None, :7]
    diff[..., 6] = heading_difference(measured[None, :, 6], predicted[:, None, 6])
    inverse = np.linalg.inv(innovation)
    return np.sqrt(np.maximum(np.einsum("nmi,nij,nmj->nm", diff, inverse, diff), 0.0))


def _footprint_bounds(tracks: np.ndarray, detections: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre distance d and sum of circumradii (N, M) [m]: footprints with d ≥ the sum cannot overlap."""
    radius = 0.5 * np.hypot(tracks[:, 3], tracks[:, 4])[:, None] + 0.5 * np.hypot(detections[:, 3], detections[:, 4])
    return bev_distance(tracks, detections), radius


def _pair_overlap(tracks: np.ndarray, detections: np.ndarray, rows: np.ndarray, cols: np.ndarray, bev: bool,
                  hull: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Intersection, union and (with ``hull``) enclosing size of the pairs ``(rows[k], cols[k])``: areas [m²]
    with ``bev``, volumes [m³] otherwise (intersection = footprint intersection × height overlap; enclosing =
    convex hull of both footprints × the union of the height ranges)."""
    corners_a, corners_b = bev_corners(tracks), bev_corners(detections)
    used_a, at_a = np.unique(rows, return_inverse=True)  # polygons only of the boxes in some pair
    used_b, at_b = np.unique(cols, return_inverse=True)
    poly_a, poly_b = shapely.polygons(corners_a[used_a]), shapely.polygons(corners_b[used_b])
    intersection = shapely.area(shapely.intersection(poly_a[at_a], poly_b[at_b]))
    enclosing = None
    if hull:
        both = np.concatenate([corners_a[rows], corners_b[cols]], axis=1)
        enclosing = shapely.area(shapely.convex_hull(shapely.multipoints(both)))
    area_a, area_b = tracks[rows, 3] * tracks[rows, 4], detections[cols, 3] * detections[cols, 4]
    if bev:
        return intersection, area_a + area_b - intersection, enclosing
    top_a, bottom_a = tracks[rows, 2] + tracks[rows, 5] / 2, tracks[rows, 2] - tracks[rows, 5] / 2
    top_b, bottom_b = detections[cols, 2] + detections[cols, 5] / 2, detections[cols, 2] - detections[cols, 5] / 2
    inter = intersection * np.maximum(0.0, np.minimum(top_a, top_b) - np.maximum(bottom_a, bottom_b))
    union = area_a * tracks[rows, 5] + area_b * detections[cols, 5] - inter
    if hull:
        enclosing = enclosing * (np.maximum(top_a, top_b) - np.minimum(bottom_a, bottom_b))
    return inter, union, enclosing


def iou(tracks: np.ndarray, detections: np.ndarray, *, bev: bool = False) -> np.ndarray:
    """IoU of rotated boxes (N, M): 3D by default, footprints only with ``bev`` — the IoU of :func:`overlaps`,
    without its enclosing hulls, and computed only for pairs whose circumcircles overlap (the others are 0
    exactly)."""
    out = np.zeros((len(tracks), len(detections)))
    if out.size == 0:
        return out
    rows, cols = np.nonzero(may_overlap(tracks, detections))
    out[rows, cols] = pair_iou(tracks, detections, rows, cols, bev=bev)
    return out


def may_overlap(tracks: np.ndarray, detections: np.ndarray) -> np.ndarray:
    """(N, M): whether the footprints' circumcircles overlap — false pairs have IoU 0 exactly."""
    d, radius = _footprint_bounds(tracks, detections)
    return d < radius


def pair_iou(tracks: np.ndarray, detections: np.ndarray, rows: np.ndarray, cols: np.ndarray, *,
             bev: bool = False) -> np.ndarray:
    """IoU of the pairs ``(tracks[rows[k]], detections[cols[k]])``, ``(K,)`` — the values :func:`iou` gives
    them, for callers that need only some pairs.

    >>> box = np.array([[0.0, 0.0, 0.0, 4.0, 2.0, 1.5, 0.0]])
    >>> pair_iou(box, box + [1.0, 0, 0, 0, 0, 0, 0], np.array([0]), np.array([0]), bev=True).round(4).tolist()
    [0.6]
    """
    if not len(rows):
        return np.zeros(0)
    inter, union, _ = _pair_overlap(tracks, detections, rows, cols, bev, hull=False)
    return inter / union


def overlaps(
    tracks: np.ndarray, detections: np.ndarray, *, bev: bool = False, floor: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """IoU and GIoU (Eq. 5 of SAGA-Track) of rotated boxes, each (N, M).

    3D (default): intersection = footprint intersection area × height overlap; enclosing shape = convex hull
    of both footprints × the union of the height ranges (AB3DMOT's 3D GIoU). ``bev=True``: footprints only.
    Footprint geometry is shapely's. With ``floor``, pairs whose GIoU is provably below ``floor`` are not
    computed: their GIoU is reported as −inf (and their IoU, 0, is exact). The proof: disjoint footprints
    (centre distance d > sum of circumradii) have GIoU ≤ (A₁ + A₂)/hull − 1 and the hull holds a triangle of
    area ρ·d, ρ the larger inscribed radius. Callers that need the IoU alone use :func:`iou`.
    """
    n, m = len(tracks), len(detections)
    iou_out = np.zeros((n, m))
    giou = np.full((n, m), -np.inf)
    if n == 0 or m == 0:
        return iou_out, giou
    d, radius = _footprint_bounds(tracks, detections)
    areas = (tracks[:, 3] * tracks[:, 4])[:, None] + (detections[:, 3] * detections[:, 4])[None, :]
    inscribed = 0.5 * np.maximum(np.minimum(tracks[:, 3], tracks[:, 4])[:, None],
                                 np.minimum(detections[:, 3], detections[:, 4])[None, :])
    if floor is None:
        candidate = np.ones((n, m), dtype=bool)
    else:
        surely_below = (d > radius) & (areas / np.maximum(inscribed * d, 1e-12) - 1.0 < floor)
        candidate = ~surely_below
    rows, cols = np.nonzero(candidate)
    if len(rows) == 0:
        return iou_out, giou
    inter, union, enclosing = _pair_overlap(tracks, detections, rows, cols, bev, hull=True)
    iou_out[rows, cols] = inter / union
    giou[rows, cols] = inter / union - (enclosing - union) / enclosing
    return iou_out, giou


def enlarged(boxes: np.ndarray, factor: float) -> np.ndarray:
    """Boxes with length, width and height scaled by ``factor`` (MUTR3D's basic baseline uses 1.2)."""
    out = boxes.copy()
    out[:, 3:6] *= factor
    return out
