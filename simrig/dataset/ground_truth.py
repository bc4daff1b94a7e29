"""The one reader of a dataset's ground truth: every consumer (scorer, exports, figures, the per-frame records
of :meth:`~simrig.dataset.Dataset.ground_truth_frames`) reads it through :func:`load_ground_truth`.

Row ``r`` is one (frame, actor) of the ``ground_truth`` table, in its order (sorted by frame). Per-camera
arrays are ``(R, C)`` in rig order. Cause masks are :class:`~simrig.causes.Cause` bit flags.
Also here: :func:`project_tracks`, a 3D tracker's boxes projected into the cameras exactly as the ground
truth's own boxes were, so that the scorer and the exports compare the same pixels.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from ..causes import CAUSE_BITS, CAUSE_NAMES, Cause
from ..errors import DatasetError
from ..geometry import as_estimated, project_boxes_at
from ..types import BOX2D_FIELDS, BOX3D_FIELDS, EGO_ID, CameraGroundTruth, Collision, EgoPose, GroundTruthFrame, Rig
from .arrow_columns import shared_strings, string_codes
from .tables import SCHEMAS
from .tracks_file import TrackRows

if TYPE_CHECKING:
    from .reader import Dataset

CAUSE_DTYPE = np.int32
"""The type of :attr:`GroundTruth.causes`' bit masks: room for 31 :class:`~simrig.causes.Cause` bits, half the
bytes of int64 (it is ``(R, C)``, one of the largest arrays a long dataset's ground truth holds)."""


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Exact ground truth of a dataset, flat.

    frames: ``(F,)`` frame numbers; timestamps ``(F,)`` [s]; egos: the ego pose per frame; events: the
    perturbation events active per frame. frame, actor_id, label: ``(R,)``; boxes: ``(R, 9)`` world boxes
    (:data:`~simrig.types.BOX3D_FIELDS`). Per camera, ``(R, C)`` in rig order: in_view; causes: every cause
    recorded for the actor in that camera (:data:`CAUSE_DTYPE` bit masks); detected: whether that camera's
    detector reported it. source_ignored: ``(R, C)`` what the source of an imported dataset marks each box as
    (0: nothing; 1 + an index into :data:`SOURCE_KINDS`: a distractor — a MOTChallenge distractor class, KITTI
    ``DontCare`` — or ground truth its benchmark does not evaluate), or ``None`` when it marks none.
    causes_known: ``False`` for imported ground truth, which records no sensor and so no causes (an error's
    cause is then ``unknown``, never ``none``). capture_offsets: ``(F, C)`` [s] each camera's true capture time
    minus its frame's tick (NaN where the camera took no image), when the scenario sets capture timing (each
    camera's 2D ground truth is at its capture time; the 3D ground truth at the tick), else ``None``. given_egos:
    the ego pose the tracker was given per frame when the scenario sets an ego-pose error (``egos`` keeps the
    true one), else ``None``. collisions: ``(frame, Collision)`` in the order of the ``collisions`` table; a
    dataset made before collisions were recorded gives its manifest's ``ego_crashed`` events instead, as
    ``Collision(EGO_ID, EGO_ID, nan, geometry=False, highway_env=True)`` (highway-env's flag; the other party was
    not recorded).

    What exists only where the actor is in view is held for those ``V`` (row, camera) pairs alone, in
    row-major order (that of ``np.nonzero(in_view)``, the tables' own; a long run has most actors out of most
    cameras): view_boxes2d ``(V, 4)`` pixel boxes; view_truncation ``(V,)`` [0, 1] (fraction of the unclipped
    projected box outside the image); view_occlusion ``(V,)`` [0, 1] (1 − visible / silhouette pixels; NaN:
    not rendered). :meth:`boxes2d_in` picks boxes of one camera; :attr:`boxes2d`, :attr:`truncation` and
    :attr:`occlusion` form the dense ``(R, C)`` arrays (NaN where not in view, as the tables have them).

    Not held, as nothing that judges tracks reads them: each box's depth (:func:`load_depth` reads it) and the
    detector's probability of each detection (in the ``sensor_truth`` table).
    """

    rig: Rig
    frames: np.ndarray
    timestamps: np.ndarray
    egos: tuple[EgoPose, ...]
    events: tuple[tuple[str, ...], ...]
    frame: np.ndarray
    actor_id: np.ndarray
    label: np.ndarray
    boxes: np.ndarray
    in_view: np.ndarray
    view_boxes2d: np.ndarray
    view_truncation: np.ndarray
    view_occlusion: np.ndarray
    causes: np.ndarray
    detected: np.ndarray
    source_ignored: np.ndarray | None = None
    causes_known: bool = True
    capture_offsets: np.ndarray | None = None
    given_egos: tuple[EgoPose, ...] | None = None
    collisions: tuple[tuple[int, Collision], ...] = ()

    def view_index(self, rows: np.ndarray, camera: int) -> np.ndarray:
        """Index into the ``view_*`` arrays of each of ``rows`` in camera ``camera`` (rig order); a ``KeyError``
        for a row that camera does not see."""
        flat = np.asarray(rows, dtype=np.int64) * self.in_view.shape[1] + camera
        position = np.searchsorted(self._view_flat, flat)
        found = position < len(self._view_flat)
        found[found] = self._view_flat[position[found]] == flat[found]
        if not found.all():
            raise KeyError(f"some rows are not in view of camera {camera}")
        return position

    def boxes2d_in(self, rows: np.ndarray, camera: int) -> np.ndarray:
        """``(n, 4)`` pixel boxes of ``rows`` (all in view) in camera ``camera`` (rig order)."""
        return self.view_boxes2d[self.view_index(rows, camera)].reshape(-1, 4)

    @property
    def boxes2d(self) -> np.ndarray:
        """``(R, C, 4)`` pixel boxes, NaN where not in view: formed on each call (a long run's is large; the
        scorer and exports use :meth:`boxes2d_in`)."""
        return self._dense(self.view_boxes2d)

    @property
    def truncation(self) -> np.ndarray:
        """``(R, C)`` truncation [0, 1], NaN where not in view (formed on each call)."""
        return self._dense(self.view_truncation)

    @property
    def occlusion(self) -> np.ndarray:
        """``(R, C)`` occlusion ratio [0, 1], NaN where not in view or not rendered (formed on each call)."""
        return self._dense(self.view_occlusion)

    def _dense(self, values: np.ndarray) -> np.ndarray:
        dense = np.full((*self.in_view.shape, *values.shape[1:]), np.nan)
        dense[self.in_view] = values
        return dense

    @cached_property
    def _view_flat(self) -> np.ndarray:
        """``(V,)`` flat index ``row · C + camera`` of each pair in view (increasing)."""
        return np.flatnonzero(self.in_view)

    def miss_causes(self, camera: int) -> np.ndarray:
        """``(R,)`` why camera ``camera`` (index in rig order) did not deliver the actor: its causes where it
        was missed, 0 where it was detected (an error there is the tracker's own)."""
        return np.where(self.detected[:, camera], 0, self.causes[:, camera])

    @property
    def miss_causes_3d(self) -> np.ndarray:
        """``(R,)`` why no camera delivered the actor: 0 if some camera detected it; else the union of the
        causes of the cameras that had it in view, or ``out_of_view`` when none had."""
        seen = self.in_view.any(axis=1)
        in_view_causes = np.bitwise_or.reduce(np.where(self.in_view, self.causes, 0), axis=1)
        union = np.where(seen, in_view_causes & ~int(Cause.OUT_OF_VIEW), int(Cause.OUT_OF_VIEW))
        return np.where(self.detected.any(axis=1), 0, union)

    @cached_property
    def camera_sets(self) -> np.ndarray:
        """``(R,)`` bit mask of the cameras that have the actor in view (bit c: camera c in rig order)."""
        sets = np.zeros(len(self.in_view), dtype=np.int64)
        for camera in range(self.in_view.shape[1]):  # one (R,) temporary at a time
            sets[self.in_view[:, camera]] |= 1 << camera
        return sets

    @cached_property
    def ego_distance(self) -> np.ndarray:
        """``(R,)`` bird's-eye-view distance [m] of each box centre from the ego at its frame."""
        return self.distance_from_ego(self.frame, self.boxes[:, :2])

    def distance_from_ego(self, frame: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """BEV distance [m] of world points ``(n, 2)`` at frame numbers ``(n,)`` from the ego at that frame."""
        position = np.searchsorted(self.frames, frame)
        ego_xy = np.array([(ego.x, ego.y) for ego in self.egos]).reshape(-1, 2)[position]
        return np.hypot(xy[:, 0] - ego_xy[:, 0], xy[:, 1] - ego_xy[:, 1])

    def frame_rows(self, position: int) -> slice:
        """The rows of the ``position``-th frame (rows are sorted by frame)."""
        lo, hi = np.searchsorted(self.frame, [self.frames[position], self.frames[position] + 1])
        return slice(int(lo), int(hi))

    def rows_of(self, frame: np.ndarray, actor_id: np.ndarray) -> np.ndarray:
        """Row index of each (frame, actor id) pair; a ``KeyError`` for a pair not in the ground truth."""
        key = self._keys(np.asarray(frame), np.asarray(actor_id))
        if len(key) and len(self._sorted_keys) == 0:
            raise KeyError("some (frame, actor) pairs are not in the ground truth")
        position = np.searchsorted(self._sorted_keys, key)
        position = np.minimum(position, len(self._sorted_keys) - 1)
        if len(key) and not np.all(self._sorted_keys[position] == key):
            raise KeyError("some (frame, actor) pairs are not in the ground truth")
        return self._key_order[position]

    def _keys(self, frame: np.ndarray, actor_id: np.ndarray) -> np.ndarray:
        return frame.astype(np.int64) * (int(self.actor_id.max(initial=0)) + 1) + actor_id.astype(np.int64)

    @cached_property
    def _key_order(self) -> np.ndarray:
        return np.argsort(self._keys(self.frame, self.actor_id), kind="stable")

    @cached_property
    def _sorted_keys(self) -> np.ndarray:
        return self._keys(self.frame, self.actor_id)[self._key_order]


def per_label(labels: np.ndarray, value_of) -> np.ndarray:
    """``(n,)`` ``value_of(label)`` [float] of each of ``labels`` (class names), called once per class present;
    no temporary but a mask per class (a long run has 200,000 rows of 2–4 classes).

    >>> per_label(np.array(["car", "bus", "car"], dtype=object), {"car": 50.0, "bus": 60.0}.get).tolist()
    [50.0, 60.0, 50.0]
    """
    values = np.empty(len(labels))
    for label in set(labels):
        values[labels == label] = value_of(str(label))
    return values


def _read_columns(dataset: Dataset, table: str, names: tuple[str, ...], rows: int, *,
                  per_camera: int | None = None, into: dict[str, np.ndarray] | None = None,
                  keep: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Columns ``names`` of ``table`` as ``(rows,)`` arrays of their schema's type, filled a row group at a time
    (nothing but the arrays is held). ``per_camera``: the table is per (frame, actor, camera), written
    actor-major in rig order; ``rows`` actors × ``per_camera`` cameras rows, a :class:`DatasetError` otherwise.
    ``keep``: a mask over the table's rows; only the rows it keeps are read into the arrays (of its count of
    ``True``). ``into``: arrays of the caller's (e.g. the strided columns of one ``(n, 4)`` array) that columns
    of the same names are written into, so that no second copy of them is made; those are not returned."""
    expected = rows if per_camera is None else rows * per_camera  # a dataset without cameras: none per camera
    found = dataset.num_rows(table)
    if per_camera is not None and found != expected:
        raise DatasetError(f"{dataset.path}: {found} rows of per-camera truth for {rows} actors × {per_camera} "
                           "cameras")
    if found != expected:
        raise DatasetError(f"{dataset.path}: {table} has {found} rows, {expected} expected")
    schema = SCHEMAS[table]
    into = into or {}
    size = expected if keep is None else int(np.count_nonzero(keep))
    out = {name: np.empty(size, dtype=schema.field(name).type.to_pandas_dtype()) for name in names}
    start = kept = 0
    for group in dataset.batches(table, [*names, *into]):
        stop = start + len(group)
        mask = None if keep is None else keep[start:stop]
        count = len(group) if mask is None else int(np.count_nonzero(mask))
        for name, array in (*out.items(), *into.items()):
            values = group.column(name).to_numpy(zero_copy_only=False)
            array[kept:kept + count] = values if mask is None else values[mask]
        start, kept = stop, kept + count
    return out


def _strings(dataset: Dataset, table: str, name: str) -> np.ndarray:
    """``(R,)`` object array of a string column (:func:`~simrig.dataset.arrow_columns.shared_strings`), read a row
    group at a time."""
    parts = [shared_strings(group.column(name)) for group in dataset.batches(table, [name])]
    return np.concatenate(parts) if parts else np.zeros(0, dtype=object)


def _cause_masks(column: pa.ChunkedArray) -> np.ndarray:
    """``(R,)`` cause bit masks of a list<string> column of cause names (:func:`simrig.causes.cause_masks`,
    vectorised); a :class:`DatasetError` for a name that is not a cause."""
    column = column.combine_chunks()
    names = pc.dictionary_encode(pc.list_flatten(column))
    lookup = dict(zip(CAUSE_NAMES, CAUSE_BITS.tolist(), strict=True))
    unknown = sorted(set(names.dictionary.to_pylist()) - set(lookup))
    if unknown:
        raise DatasetError(f"sensor_truth: unknown cause(s) {unknown}")
    bits = np.array([lookup[name] for name in names.dictionary.to_pylist()], dtype=np.int64)
    masks = np.zeros(len(column), dtype=np.int64)
    if len(bits):
        np.add.at(masks, pc.list_parent_indices(column).to_numpy(), bits[names.indices.to_numpy()])
    return masks


SOURCE_KINDS = ("distractor", "unevaluated")
"""What an imported dataset's source marks a box as (the ``kind`` column of ``source_ignored.parquet``): a
distractor (a tracker box matched to it is removed) or ground truth its benchmark does not evaluate (a tracker
box matched to it is kept). :attr:`GroundTruth.source_ignored` holds 1 + the kind's index, 0 for none."""


def _source_ignored(dataset: Dataset, n: int, c: int) -> np.ndarray | None:
    """``(n, c)`` rule bits of the boxes an imported dataset's source marks as not scored, or ``None`` when it
    marks none."""
    table = dataset.source_ignored_table()
    if table is None or table.num_rows == 0:
        return None
    truth = dataset.table("ground_truth")
    frame = truth.column("frame").to_numpy().astype(np.int64)
    actor = truth.column("actor_id").to_numpy()
    key = frame * (int(actor.max(initial=0)) + 1) + actor
    order = np.argsort(key, kind="stable")
    wanted = (table.column("frame").to_numpy().astype(np.int64) * (int(actor.max(initial=0)) + 1)
              + table.column("actor_id").to_numpy())
    position = np.clip(np.searchsorted(key[order], wanted), 0, max(n - 1, 0))
    if n == 0 or np.any(key[order][position] != wanted):
        raise DatasetError(f"{dataset.path}: source_ignored lists a (frame, actor) that is not in the ground truth")
    camera_of = {name: i for i, name in enumerate(dataset.rig.camera_names)}
    kinds = table.column("kind").to_pylist()
    unknown = sorted(set(kinds) - set(SOURCE_KINDS))
    if unknown:
        raise DatasetError(f"{dataset.path}: source_ignored kind {unknown[0]!r} (kinds: {', '.join(SOURCE_KINDS)})")
    marked = np.zeros((n, c), dtype=np.int8)
    marked[order[position], [camera_of[name] for name in table.column("camera").to_pylist()]] = [
        1 + SOURCE_KINDS.index(kind) for kind in kinds]
    return marked


def load_ground_truth(dataset: Dataset) -> GroundTruth:
    """Read the ground truth, projections, visibility and sensor truth of ``dataset`` into a
    :class:`GroundTruth` (vectorised; one pass over each table, a row group at a time, nothing kept but the
    arrays)."""
    rig = dataset.rig
    cameras = rig.camera_names
    c = len(cameras)
    ego = dataset.columns("ego_poses")
    frames = ego.column("frame").to_numpy().astype(np.int64)
    ego_columns = {name: ego.column(name).to_numpy() for name in ("x", "y", "z", "yaw", "vx", "vy")}
    egos = tuple(EgoPose(*(float(ego_columns[name][i]) for name in ego_columns)) for i in range(len(frames)))
    n = dataset.num_rows("ground_truth")
    boxes = np.empty((n, 9))
    truth = _read_columns(dataset, "ground_truth", ("frame", "actor_id"), n,
                          into={name: boxes[:, i] for i, name in enumerate(BOX3D_FIELDS)})
    in_view = _read_columns(dataset, "projections", ("in_view",), n, per_camera=c)["in_view"]
    boxes2d = np.empty((int(np.count_nonzero(in_view)), 4))
    truncation = _read_columns(dataset, "projections", ("truncation",), n, per_camera=c, keep=in_view,
                               into={name: boxes2d[:, i] for i, name in enumerate(BOX2D_FIELDS)})["truncation"]
    ground_truth = GroundTruth(
        rig=rig,
        frames=frames,
        timestamps=ego.column("timestamp").to_numpy(),
        egos=egos,
        events=tuple(tuple(row) for row in dataset.columns("frames", ["events"]).column("events").to_pylist()),
        frame=truth.pop("frame").astype(np.int64),
        actor_id=truth.pop("actor_id"),
        label=_strings(dataset, "ground_truth", "class"),
        boxes=boxes,
        in_view=in_view.reshape(n, c),
        view_boxes2d=boxes2d,
        view_truncation=truncation,
        view_occlusion=_read_columns(dataset, "visibility", ("occlusion",), n, per_camera=c,
                                     keep=in_view)["occlusion"],
        causes=np.zeros((n, c), dtype=CAUSE_DTYPE),
        detected=np.zeros((n, c), dtype=bool),
        source_ignored=_source_ignored(dataset, n, c),
        causes_known=dataset.causes_known,
        capture_offsets=_capture_offsets(dataset, ego.column("timestamp").to_numpy(), c),
        given_egos=_given_egos(dataset, len(frames)),
        collisions=_collisions(dataset),
    )
    camera_of = {name: i for i, name in enumerate(cameras)}
    for sensor in dataset.batches("sensor_truth", ["frame", "camera", "actor_id", "detection", "causes"]):
        actor = sensor.column("actor_id").to_numpy()
        real = actor >= 0
        if not real.any():
            continue
        rows = ground_truth.rows_of(sensor.column("frame").to_numpy()[real], actor[real])
        camera = string_codes(sensor.column("camera"), camera_of, f"{dataset.path}: sensor_truth camera")[real]
        ground_truth.causes[rows, camera] = _cause_masks(sensor.column("causes"))[real]
        ground_truth.detected[rows, camera] = sensor.column("detection").to_numpy()[real] >= 0
    return ground_truth


def _capture_offsets(dataset: Dataset, timestamps: np.ndarray, cameras: int) -> np.ndarray | None:
    """``(F, C)`` [s] true capture time − tick of every frame and camera, from the ``captures`` table (rows by
    frame, then camera in rig order); ``None`` for a dataset without one."""
    if not dataset.has_table("captures"):
        return None
    table = dataset.columns("captures", ["capture_time", "fired"])
    times = np.where(table.column("fired").to_numpy(zero_copy_only=False), table.column("capture_time").to_numpy(),
                     np.nan)
    if len(times) != len(timestamps) * cameras:
        raise DatasetError(f"dataset {str(dataset.path)!r}: captures holds {len(times)} rows, not one per frame "
                           f"and camera ({len(timestamps)} × {cameras})")
    return times.reshape(len(timestamps), cameras) - timestamps[:, None]


def _collisions(dataset: Dataset) -> tuple[tuple[int, Collision], ...]:
    """The ``collisions`` table's rows as ``(frame, Collision)``; for a dataset without one, its manifest's
    ``ego_crashed`` events (:class:`GroundTruth`)."""
    if not dataset.has_table("collisions"):
        return tuple((int(event["frame"]), Collision(EGO_ID, EGO_ID, float("nan"), geometry=False, highway_env=True))
                     for event in dataset.manifest.get("events", []) if event.get("event") == "ego_crashed")
    table = dataset.columns("collisions")
    columns = [table.column(name).to_pylist() for name in
               ("frame", "first", "second", "closing_speed", "geometry", "highway_env")]
    return tuple((int(frame), Collision(int(first), int(second), float(speed), bool(geometry), bool(flag)))
                 for frame, first, second, speed, geometry, flag in zip(*columns, strict=True))


def _given_egos(dataset: Dataset, frames: int) -> tuple[EgoPose, ...] | None:
    """The ``ego_estimates`` table's poses (one per frame), or ``None`` for a dataset without one."""
    if not dataset.has_table("ego_estimates"):
        return None
    table = dataset.columns("ego_estimates")
    if table.num_rows != frames:
        raise DatasetError(f"dataset {str(dataset.path)!r}: ego_estimates holds {table.num_rows} rows, not one per "
                           f"frame ({frames})")
    columns = [table.column(name).to_numpy() for name in ("x", "y", "z", "yaw", "vx", "vy")]
    return tuple(EgoPose(*(float(column[i]) for column in columns)) for i in range(frames))


def relative_to_true_ego(truth: GroundTruth, tracks3d: TrackRows) -> TrackRows:
    """3D tracks of a tracker given an estimated ego pose, put in the true world frame for scoring: each frame's
    boxes keep where they are relative to the ego, moved from the pose the tracker was given to the true pose
    (what a car acts on is where an object is relative to it; the pose estimate's own error is not the
    tracker's). The tracks unchanged when the dataset has no ego-pose error."""
    if truth.given_egos is None or not len(tracks3d):
        return tracks3d
    boxes = np.array(tracks3d.boxes, dtype=float, copy=True)
    position = np.searchsorted(truth.frames, tracks3d.frame)
    known = (position < len(truth.frames)) & (truth.frames[np.minimum(position, len(truth.frames) - 1)]
                                              == tracks3d.frame)
    for index in np.unique(position[known]):
        rows = known & (position == index)
        # as_estimated maps the other way round here: from the given pose's world to the true one's
        boxes[rows] = as_estimated(boxes[rows], truth.given_egos[index], truth.egos[index])
    return TrackRows(tracks3d.frame, tracks3d.track_id, tracks3d.label, tracks3d.score, boxes, tracks3d.camera)


def load_depth(dataset: Dataset) -> np.ndarray:
    """``(R, C)`` camera-frame depth [m] of every (frame, actor) row of the ground truth in every camera (rig
    order), read a row group at a time: what :class:`GroundTruth` does not hold."""
    n, c = dataset.num_rows("ground_truth"), len(dataset.rig.camera_names)
    return _read_columns(dataset, "projections", ("depth",), n, per_camera=c)["depth"].reshape(n, c)


def project_tracks(truth: GroundTruth, tracks3d: TrackRows, *, chunk_frames: int = 256) -> TrackRows:
    """2D rows of 3D tracks: each box projected into every camera at its frame's ego pose with the ground
    truth's geometry (:func:`simrig.geometry.project_boxes`: clipped to the near plane and the image), kept
    where in view — with capture timing, at each camera's capture time (the box moved with its own velocity,
    the camera with the ego's), where that camera's ground truth is; sorted by frame, then track row, then
    camera. Tracks at frames the ground truth lacks have no 2D rows. Projects ``chunk_frames`` frames per call
    (bounded memory)."""
    frame, camera, index, boxes = [], [], [], []
    names = np.array(truth.rig.camera_names, dtype=object)
    starts = np.searchsorted(tracks3d.frame, truth.frames)
    stops = np.searchsorted(tracks3d.frame, truth.frames, side="right")
    for first in range(0, len(truth.frames) if names.size else 0, chunk_frames):  # a rig without cameras: none
        chunk = slice(first, first + chunk_frames)
        counts = stops[chunk] - starts[chunk]
        if not counts.sum():
            continue
        rows = np.concatenate([np.arange(lo, hi) for lo, hi in zip(starts[chunk], stops[chunk], strict=True)])
        pose = np.repeat(np.arange(len(counts)), counts)
        offsets = None if truth.capture_offsets is None else truth.capture_offsets[chunk]
        projection = project_boxes_at(tracks3d.boxes[rows], truth.rig, truth.egos[chunk], pose,
                                      None if offsets is None else np.nan_to_num(offsets))
        in_view = projection.in_view if offsets is None else projection.in_view & np.isfinite(offsets[pose]).T
        cam, box = np.nonzero(in_view)  # a camera that took no image at a frame sees no track there
        order = np.lexsort((cam, box))  # by track row, then camera: stays sorted by frame
        cam, box = cam[order], box[order]
        frame.append(truth.frames[chunk][pose[box]])
        camera.append(names[cam])
        index.append(rows[box])
        boxes.append(projection.boxes[cam, box])
    if not index:
        return TrackRows(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, object), np.zeros(0),
                         np.zeros((0, 4)), np.zeros(0, object))
    index = np.concatenate(index)
    return TrackRows(
        frame=np.concatenate(frame),
        track_id=tracks3d.track_id[index],
        label=tracks3d.label[index],
        score=tracks3d.score[index],
        boxes=np.concatenate(boxes),
        camera=np.concatenate(camera),
    )


def ground_truth_frames(dataset: Dataset) -> Iterator[GroundTruthFrame]:
    """Every frame's :class:`GroundTruthFrame`, in order, with per-camera projections: views on the dataset's
    :attr:`~simrig.dataset.Dataset.ground_truth`."""
    truth = dataset.ground_truth
    boxes2d, truncation, occlusion, depth = truth.boxes2d, truth.truncation, truth.occlusion, load_depth(dataset)
    collisions: dict[int, list] = {}
    for frame, collision in truth.collisions:
        collisions.setdefault(frame, []).append(collision)
    for position, frame in enumerate(truth.frames):
        rows = truth.frame_rows(position)
        per_camera = {
            name: CameraGroundTruth(
                boxes=boxes2d[rows, index],
                truncation=truncation[rows, index],
                depth=depth[rows, index],
                in_view=truth.in_view[rows, index],
                occlusion=occlusion[rows, index],
            )
            for index, name in enumerate(truth.rig.camera_names)
        }
        yield GroundTruthFrame(
            frame=int(frame),
            timestamp=float(truth.timestamps[position]),
            ego=truth.egos[position],
            actor_ids=truth.actor_id[rows],
            classes=truth.label[rows],
            boxes=truth.boxes[rows],
            cameras=per_camera,
            events=truth.events[position],
            collisions=tuple(collisions.get(int(frame), ())),
        )
