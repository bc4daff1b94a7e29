"""Tracks on disk: the Parquet format of a tracker's output, so that any tracker, in any language, can be scored.

A tracks folder holds one or both of

``tracks3d.parquet``  one row per (frame, track) of a 3D tracker, world frame:
                      ``frame`` int, ``track_id`` int, ``class`` string, ``score`` float,
                      ``x, y, z`` [m] box centre, ``length, width, height`` [m] (> 0), ``yaw`` [rad] CCW from +x,
                      ``vx, vy`` [m/s].
``tracks2d.parquet``  one row per (frame, camera, track) of a 2D tracker (or a 3D tracker's own per-camera boxes):
                      ``frame`` int, ``camera`` string, ``track_id`` int, ``class`` string, ``score`` float,
                      ``x1, y1, x2, y2`` [px] from the image's top-left corner (x2 > x1, y2 > y1).

A single ``.parquet`` file of either layout may be given instead of a folder. Classes are simrig's
(``car``, ``truck``, ``bus``, ``motorcycle``). Rows may come in any order. Reading rejects, naming the file,
column and row: a missing or unknown column, a null, a non-finite number, an unknown class or camera, a frame
outside the dataset, an empty box, and a track id used twice in one frame (per camera in 2D).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from simrig.errors import TracksError
from simrig.reading import check_regular
from simrig.types import BOX2D_FIELDS, BOX3D_FIELDS, ActorClass, Track

from .arrow_columns import shared_strings
from .outputs import atomic_file

MADE_ON_KEY = b"simrig.made_on"
"""The Parquet metadata key of a tracks table that holds the identity (JSON) of the dataset it was made on."""
TRACKS3D_FILE = "tracks3d.parquet"
TRACKS2D_FILE = "tracks2d.parquet"
_KEYS3D = ("frame", "track_id", "class", "score")
_KEYS2D = ("frame", "camera", "track_id", "class", "score")
TRACKS3D_SCHEMA = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("track_id", pa.int64()), pa.field("class", pa.string()),
     pa.field("score", pa.float64())] + [pa.field(name, pa.float64()) for name in BOX3D_FIELDS],
    metadata={"frame": "world: x along the road, y left, z up [m]; yaw [rad] CCW from +x; v [m/s]"},
)
TRACKS2D_SCHEMA = pa.schema(
    [pa.field("frame", pa.int32()), pa.field("camera", pa.string()), pa.field("track_id", pa.int64()),
     pa.field("class", pa.string()), pa.field("score", pa.float64())]
    + [pa.field(name, pa.float64()) for name in BOX2D_FIELDS],
    metadata={"units": "pixel box (x1, y1, x2, y2) from the image's top-left corner"},
)
CLASSES = tuple(c.value for c in ActorClass)


@dataclass(frozen=True, eq=False)
class TrackRows:
    """Validated tracker output of one layout, sorted by frame (then camera in rig order for 2D, then as read).

    frame, track_id, score: ``(R,)``; label: ``(R,)`` class names; boxes: ``(R, 9)`` world boxes
    (:data:`~simrig.types.BOX3D_FIELDS`) or ``(R, 4)`` pixel boxes; camera: ``(R,)`` names (2D) or ``None``.
    """

    frame: np.ndarray
    track_id: np.ndarray
    label: np.ndarray
    score: np.ndarray
    boxes: np.ndarray
    camera: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.frame)

    def take(self, rows: np.ndarray) -> TrackRows:
        """These rows at ``rows`` (indices or a boolean mask), in that order."""
        return TrackRows(self.frame[rows], self.track_id[rows], self.label[rows], self.score[rows], self.boxes[rows],
                         None if self.camera is None else self.camera[rows])


@dataclass(frozen=True, eq=False)
class TrackSet:
    """What a tracker produced: 3D rows, 2D rows, or both; ``source`` is the path they were read from;
    ``made_on``: the ``identity`` (a :class:`~simrig.dataset.Dataset` attribute) of the dataset they were made on,
    when simrig recorded it (tracks simrig wrote; ``None`` for other tools' files)."""

    source: str
    tracks3d: TrackRows | None
    tracks2d: TrackRows | None
    made_on: dict | None = None


class TrackTables:
    """The tables of a tracker's output, built frame by frame: :meth:`add` turns one frame's tracks into column
    arrays at once (a few numbers per track, so a long run does not hold its :class:`~simrig.types.Track`
    objects); :meth:`tables` joins them."""

    def __init__(self) -> None:
        self._parts3d: list[tuple[np.ndarray, ...]] = []
        self._parts2d: list[tuple[np.ndarray, ...]] = []

    def add(self, frame: int, tracks: Iterable[Track]) -> None:
        """One frame's tracks (as a tracker returned them)."""
        ids3d, labels3d, scores3d, boxes3d = [], [], [], []
        cameras, ids2d, labels2d, scores2d, boxes2d = [], [], [], [], []
        for track in tracks:
            label = ActorClass(track.label).value
            if track.box3d is not None:
                ids3d.append(track.track_id)
                labels3d.append(label)
                scores3d.append(track.score)
                boxes3d.append(track.box3d.as_array())
            for camera, box in track.boxes2d.items():
                cameras.append(camera)
                ids2d.append(track.track_id)
                labels2d.append(label)
                scores2d.append(track.score)
                boxes2d.append(box.as_array())
        if ids3d:
            self._parts3d.append((np.full(len(ids3d), frame, dtype=np.int64), np.array(ids3d, dtype=np.int64),
                                  np.array(labels3d, dtype=object), np.array(scores3d, dtype=float),
                                  np.stack(boxes3d)))
        if ids2d:
            self._parts2d.append((np.full(len(ids2d), frame, dtype=np.int64), np.array(cameras, dtype=object),
                                  np.array(ids2d, dtype=np.int64), np.array(labels2d, dtype=object),
                                  np.array(scores2d, dtype=float), np.stack(boxes2d)))

    def tables(self) -> dict[str, pa.Table]:
        """The tables by file name: ``tracks3d.parquet`` from the tracks' 3D boxes and ``tracks2d.parquet`` from
        their per-camera boxes (each present only when some track has such boxes; both, empty, when none has)."""
        tables = {}
        if self._parts3d or not self._parts2d:
            tables[TRACKS3D_FILE] = _parts_table(self._parts3d, TRACKS3D_SCHEMA, 9)
        if self._parts2d or not self._parts3d:
            tables[TRACKS2D_FILE] = _parts_table(self._parts2d, TRACKS2D_SCHEMA, 4)
        return tables


def _track_tables(frames: Iterable[tuple[int, Iterable[Track]]]) -> dict[str, pa.Table]:
    """The tables of ``(frame, tracks)`` pairs (as returned by a tracker, frame by frame), by file name
    (:meth:`TrackTables.tables`)."""
    builder = TrackTables()
    for frame, tracks in frames:
        builder.add(frame, tracks)
    return builder.tables()


def write_tracks(out: Path | str, frames: Iterable[tuple[int, Iterable[Track]]] | dict[str, pa.Table], *,
                 made_on: dict | None = None) -> Path:
    """Write ``(frame, tracks)`` pairs (or the tables :func:`_track_tables` made of them) to the folder ``out``.
    Files are written to a temporary name and renamed, so an interrupted write leaves no partial table.
    ``made_on``: the identity of the dataset the tracks were made on, kept in each table's metadata
    (:data:`MADE_ON_KEY`) so that scoring them on another dataset is refused."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tables = frames if isinstance(frames, dict) else _track_tables(frames)
    for name in (TRACKS3D_FILE, TRACKS2D_FILE):
        if name not in tables and (out / name).exists():
            (out / name).unlink()  # a stale table from an earlier run must not be scored with this one
    for name, table in tables.items():
        if made_on is not None:
            metadata = {**(table.schema.metadata or {}), MADE_ON_KEY: json.dumps(made_on, sort_keys=True).encode()}
            table = table.replace_schema_metadata(metadata)
        with atomic_file(out / name) as partial:
            pq.write_table(table, partial)
    return out


def _made_on(schema: pa.Schema, where: str = "tracks file") -> dict | None:
    """The dataset identity a tracks table's metadata records, or ``None`` when it records none; a
    :class:`TracksError` naming ``where`` when the record is there but damaged (it was taken as none, so tracks
    of another dataset could be scored without the warning the record exists for)."""
    raw = (schema.metadata or {}).get(MADE_ON_KEY)
    if raw is None:
        return None
    try:
        value = json.loads(raw)
    except (ValueError, UnicodeDecodeError) as error:
        raise TracksError(f"{where}: its {MADE_ON_KEY.decode()} record is damaged ({error}); write the tracks "
                          "again, or remove the record to score them without it") from None
    if not isinstance(value, dict):
        raise TracksError(f"{where}: its {MADE_ON_KEY.decode()} record is not a table of the dataset's identity")
    return value


def tracks_in_memory(tables: dict[str, pa.Table], *, frame_count: int, cameras: tuple[str, ...],
                     source: str = "tracker output", made_on: dict | None = None) -> TrackSet:
    """A validated :class:`TrackSet` of :func:`_track_tables`' tables, without a round trip through files:
    the same checks as :func:`read_tracks`, errors naming ``source``."""
    rows = {name: _rows(f"{source} ({name})", table.column_names, table.column, name, frame_count, cameras)
            for name, table in tables.items()}
    return TrackSet(source=source, tracks3d=rows.get(TRACKS3D_FILE), tracks2d=rows.get(TRACKS2D_FILE),
                    made_on=made_on)


def _parts_table(parts: list[tuple[np.ndarray, ...]], schema: pa.Schema, box_size: int) -> pa.Table:
    """One table of per-frame column arrays (the schema's columns before the box, then the ``(k, box_size)``
    box)."""
    keys = len(schema) - box_size
    if parts:
        columns = [np.concatenate([part[i] for part in parts]) for i in range(keys)]
        boxes = np.concatenate([part[keys] for part in parts])
    else:
        columns, boxes = [np.zeros(0, dtype=object) for _ in range(keys)], np.zeros((0, box_size))
    columns += [boxes[:, i] for i in range(box_size)]
    return pa.table([pa.array(column.tolist() if column.dtype == object else column, type=field.type)
                     for column, field in zip(columns, schema, strict=True)], schema=schema)


def rows_table(rows: list[tuple], schema: pa.Schema) -> pa.Table:
    """One table of row tuples in the schema's column order (the outside formats' readers)."""
    columns = list(zip(*rows, strict=True)) if rows else [[] for _ in schema.names]
    return pa.table([pa.array(list(column), type=field.type) for column, field in zip(columns, schema, strict=True)],
                    schema=schema)


def read_tracks(path: Path | str, *, frame_count: int, cameras: tuple[str, ...]) -> TrackSet:
    """Read and validate a tracks folder or file against a dataset of ``frame_count`` frames seen by
    ``cameras``; a :class:`~simrig.errors.TracksError` naming the file, column and row otherwise."""
    path = Path(path)
    if path.is_dir():
        files = {name: path / name for name in (TRACKS3D_FILE, TRACKS2D_FILE) if (path / name).exists()}
        if not files:
            raise TracksError(f"{path}: holds neither {TRACKS3D_FILE} nor {TRACKS2D_FILE}")
    elif path.is_file():
        files = {_layout_of(path): path}
    else:
        raise TracksError(f"tracks {str(path)!r} does not exist")
    rows, made_on = {}, None
    for name, file in files.items():
        rows[name], recorded = _read(file, name, frame_count, cameras)
        made_on = made_on or recorded
    return TrackSet(source=str(path), tracks3d=rows.get(TRACKS3D_FILE), tracks2d=rows.get(TRACKS2D_FILE),
                    made_on=made_on)


def _layout_of(file: Path) -> str:
    """Which layout a single Parquet file has: 2D if it has a ``camera`` column."""
    try:
        check_regular(file, "tracks file", TracksError)
        names = pq.read_schema(file).names
    except (pa.ArrowInvalid, OSError) as error:
        raise TracksError(f"{file}: not a readable Parquet file ({error})") from None
    return TRACKS2D_FILE if "camera" in names else TRACKS3D_FILE


def _read(file: Path, layout: str, frame_count: int, cameras: tuple[str, ...]) -> tuple[TrackRows, dict | None]:
    """Read ``file`` a column at a time, each copied out of Arrow's buffers before the next is read: a long run's
    tracks are held once, as numpy, with Arrow's memory of one column at a time on top (not the whole table's,
    which its allocator keeps after it is freed). Also the dataset identity its metadata records."""
    def unreadable(error: Exception) -> TracksError:
        return TracksError(f"{file}: not a readable Parquet file ({error})")

    try:
        check_regular(file, "tracks file", TracksError)
        parquet = pq.ParquetFile(file)
    except (pa.ArrowInvalid, OSError) as error:
        raise unreadable(error) from None

    def column(name: str) -> pa.ChunkedArray:
        try:
            return parquet.read(columns=[name]).column(0)
        except (pa.ArrowInvalid, OSError) as error:
            raise unreadable(error) from None

    rows = _rows(file, parquet.schema_arrow.names, column, layout, frame_count, cameras)
    return rows, _made_on(parquet.schema_arrow, str(file))


def _rows(file: Path | str, names: list[str], column: Callable[[str], pa.ChunkedArray], layout: str,
          frame_count: int, cameras: tuple[str, ...]) -> TrackRows:
    """Validate a table of columns ``names``, each given by ``column(name)`` (``layout``: which file it is), and
    sort it; errors name ``file``, column and row. Each column is copied out of Arrow at once (so that a column
    read from a file is freed before the next is read); rows already in order are not copied again."""
    schema = TRACKS3D_SCHEMA if layout == TRACKS3D_FILE else TRACKS2D_SCHEMA
    missing = [name for name in schema.names if name not in names]
    if missing:
        raise TracksError(f"{file}: missing column(s) {', '.join(missing)} (a {layout} file has: "
                          f"{', '.join(schema.names)})")
    unknown = [name for name in names if name not in schema.names]
    if unknown:
        raise TracksError(f"{file}: unknown column(s) {', '.join(unknown)} (a {layout} file has: "
                          f"{', '.join(schema.names)})")
    columns = {field.name: _column(file, column(field.name), field) for field in schema}
    frame, track_id = columns["frame"], columns["track_id"]

    def fail(row: int, what: str) -> None:
        where = f"row {row} (frame {frame[row]}, track {track_id[row]}"
        where += f", camera {columns['camera'][row]!r})" if "camera" in columns else ")"
        raise TracksError(f"{file}: {where}: {what}")

    numeric = [name for name in schema.names if name not in ("frame", "track_id", "class", "camera")]
    first_bad = [(int(np.argmin(finite)), col) for col, name in enumerate(numeric)
                 if not (finite := np.isfinite(columns[name])).all()]
    if first_bad:  # the first in row order, then column order
        row, col = min(first_bad)
        fail(row, f"column {numeric[col]!r} is {columns[numeric[col]][row]} (must be a finite number)")
    negative = np.nonzero(track_id < 0)[0]
    if len(negative):
        fail(int(negative[0]), f"track id {track_id[negative[0]]} is negative (ids are 0 … 2⁶³ − 1)")
    unscored = np.nonzero((columns["score"] < 0.0) | (columns["score"] > 1.0))[0]
    if len(unscored):
        fail(int(unscored[0]), f"score {columns['score'][unscored[0]]} is outside 0 … 1 (a confidence)")
    outside = np.nonzero((frame < 0) | (frame >= frame_count))[0]
    if len(outside):
        fail(int(outside[0]), f"frame {frame[outside[0]]} is not in the dataset (frames 0…{frame_count - 1})")
    unknown_class = np.nonzero(~np.isin(columns["class"], CLASSES))[0]
    if len(unknown_class):
        fail(int(unknown_class[0]), f"unknown class {columns['class'][unknown_class[0]]!r} "
                                    f"(classes: {', '.join(CLASSES)})")
    if layout == TRACKS2D_FILE:
        unknown_camera = np.nonzero(~np.isin(columns["camera"], cameras))[0]
        if len(unknown_camera):
            fail(int(unknown_camera[0]), f"unknown camera {columns['camera'][unknown_camera[0]]!r} "
                                         f"(cameras: {', '.join(cameras)})")
        boxes = np.column_stack([columns.pop(name) for name in BOX2D_FIELDS]).reshape(-1, 4)
        empty = np.nonzero((boxes[:, 2] <= boxes[:, 0]) | (boxes[:, 3] <= boxes[:, 1]))[0]
        if len(empty):
            fail(int(empty[0]), f"empty box {boxes[empty[0]].tolist()} (needs x2 > x1 and y2 > y1)")
        camera_index = np.searchsorted(np.array(cameras), columns["camera"], sorter=np.argsort(cameras))
        camera_index = np.argsort(cameras)[camera_index]
        group = (camera_index,)
    else:
        boxes = np.column_stack([columns.pop(name) for name in BOX3D_FIELDS]).reshape(-1, 9)
        flat = np.nonzero(np.any(boxes[:, 3:6] <= 0.0, axis=1))[0]
        if len(flat):
            fail(int(flat[0]), f"box size {boxes[flat[0], 3:6].tolist()} must be positive (length, width, height)")
        group = ()
    order = np.lexsort((np.arange(len(frame)), *group, frame))
    key = np.column_stack([frame, *group, track_id])[order]
    repeated = np.nonzero(np.all(key[1:] == key[:-1], axis=1))[0] if len(key) > 1 else np.zeros(0, dtype=int)
    if len(repeated):
        first, second = order[repeated[0]], order[repeated[0] + 1]
        fail(int(second), f"track id {track_id[second]} appears twice in this frame (also row {first})")
    rows = slice(None) if np.array_equal(order, np.arange(len(order))) else order  # a tracker's own file is in order
    return TrackRows(
        frame=frame[rows],
        track_id=track_id[rows],
        label=columns["class"][rows],
        score=columns["score"][rows],
        boxes=boxes[rows],
        camera=columns["camera"][rows] if layout == TRACKS2D_FILE else None,
    )


def _column(file: Path | str, column: pa.ChunkedArray, field: pa.Field) -> np.ndarray:
    """One column as a numpy array of its own (not a view on Arrow's buffers) in the field's type; errors name
    the column (and the first null's row)."""
    if column.null_count:
        row = int(pc.index(pc.is_null(column), True).as_py())
        raise TracksError(f"{file}: row {row}: column {field.name!r} is null")
    kind = column.type
    if pa.types.is_string(field.type) or pa.types.is_large_string(field.type):
        if not (pa.types.is_string(kind) or pa.types.is_large_string(kind)):
            raise TracksError(f"{file}: column {field.name!r} must hold strings, found {kind}")
        return shared_strings(column)
    if pa.types.is_integer(field.type):
        if not pa.types.is_integer(kind):
            raise TracksError(f"{file}: column {field.name!r} must hold integers, found {kind}")
        largest = np.iinfo(np.int64).max
        if pa.types.is_uint64(kind) and len(column) and pc.max(column).as_py() > largest:
            row = int(pc.index(pc.greater(column, pa.scalar(largest, pa.uint64())), True).as_py())
            raise TracksError(f"{file}: row {row}: column {field.name!r} is {column[row].as_py()}, beyond 2⁶³ − 1")
        return column.to_numpy().astype(np.int64)
    if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
        raise TracksError(f"{file}: column {field.name!r} must hold numbers, found {kind}")
    return column.to_numpy().astype(float)
