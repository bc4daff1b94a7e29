"""Reading a dataset folder back into simrig's records."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ..errors import DatasetError
from ..rig import rig_from_dict
from ..road import RoadMarkings
from ..types import (
    BOX2D_FIELDS,
    BOX3D_FIELDS,
    LABELS,
    CameraGroundTruth,
    DetectionArrays,
    EgoPose,
    GroundTruthFrame,
    Rig,
    SensorFrame,
)
from .arrow_columns import string_codes
from .ground_truth import GroundTruth, load_depth
from .manifest import MANIFEST_NAME, read_manifest
from .manifest_files import ManifestFiles
from .tables import ALL_SCHEMAS, OPTIONAL_SCHEMAS


def frame_detections(table: pa.Table, frame: int, rig: Rig, dimension: int) -> DetectionArrays:
    """What a tracker is given for ``frame`` from a ``detections`` table holding that frame's rows (as written,
    before the dataset exists: the closed-loop drive), exactly as :meth:`Dataset.sensor_frames` gives it."""
    return _DetectionChunk.of_table(table, rig, dimension, f"frame {frame}: detections").frame_arrays(frame)


def _stack(table: pa.Table, names: tuple[str, ...]) -> np.ndarray:
    """``(rows, len(names))`` float array of the named columns (``(0, len(names))`` for an empty table)."""
    return np.column_stack([table.column(name).to_numpy() for name in names])


def embedding_matrix(column: pa.ChunkedArray, dimension: int) -> np.ndarray:
    """``(R, D)`` float32 embeddings from a list<float> column whose lists hold ``dimension`` (D) values or
    none; a row of NaN where a detection has none."""
    column = column.combine_chunks()
    lengths = np.diff(column.offsets.to_numpy())
    out = np.full((len(lengths), dimension), np.nan, dtype=np.float32)
    present = lengths == dimension
    if not np.all(present | (lengths == 0)):
        raise DatasetError(f"detections: embeddings of {sorted(set(lengths.tolist()))} values; one length expected")
    if dimension:
        out[present] = column.flatten().to_numpy(zero_copy_only=False).reshape(-1, dimension)
    return out


def _image_paths(folder: Path | None, rig: Rig, frame: int) -> dict[str, str]:
    """Per camera, the path of its PNG of ``frame`` in the dataset's ``images/`` ``folder`` (none without one)."""
    return {} if folder is None else {name: str(folder / name / f"{frame:06d}.png") for name in rig.camera_names}


@dataclass(frozen=True, eq=False)
class _DetectionChunk:
    """Detections of consecutive frames as the arrays of :class:`~simrig.types.DetectionArrays` (rows sorted by
    frame): frame ``(R,)``, boxes3d ``(R, 9)`` world frame, boxes2d ``(R, 4)`` [px], scores, labels and cameras
    (codes) ``(R,)``, embeddings ``(R, D)``."""

    frame: np.ndarray
    boxes3d: np.ndarray
    boxes2d: np.ndarray
    scores: np.ndarray
    labels: np.ndarray
    cameras: np.ndarray
    embeddings: np.ndarray

    @classmethod
    def of_table(cls, table: pa.Table, rig: Rig, dimension: int, where: str) -> _DetectionChunk:
        """The rows of a ``detections`` table (:data:`~simrig.dataset.tables.DETECTIONS` columns) with embeddings of
        ``dimension`` values; ``where`` names the table in an error."""
        camera_codes = {name: code for code, name in enumerate(rig.camera_names)}
        label_codes = {label.value: code for code, label in enumerate(LABELS)}
        return cls(
            frame=table.column("frame").to_numpy(),
            boxes3d=_stack(table, BOX3D_FIELDS),
            boxes2d=_stack(table, BOX2D_FIELDS),
            scores=table.column("score").to_numpy(),
            labels=string_codes(table.column("label"), label_codes, f"{where} label"),
            cameras=string_codes(table.column("camera"), camera_codes, f"{where} camera"),
            embeddings=embedding_matrix(table.column("embedding"), dimension),
        )

    @classmethod
    def empty(cls, dimension: int) -> _DetectionChunk:
        return cls(np.zeros(0, np.int32), np.zeros((0, 9)), np.zeros((0, 4)), np.zeros(0), np.zeros(0, np.int64),
                   np.zeros(0, np.int64), np.zeros((0, dimension), np.float32))

    def _fields(self) -> tuple[np.ndarray, ...]:
        return (self.frame, self.boxes3d, self.boxes2d, self.scores, self.labels, self.cameras, self.embeddings)

    def joined(self, other: _DetectionChunk) -> _DetectionChunk:
        """This chunk's rows followed by ``other``'s."""
        return _DetectionChunk(*(np.concatenate([a, b]) for a, b in zip(self._fields(), other._fields(), strict=True)))

    @classmethod
    def concatenated(cls, chunks: list[_DetectionChunk], dimension: int) -> _DetectionChunk:
        """The rows of ``chunks`` in order, as one chunk (each array copied once)."""
        if not chunks:
            return cls.empty(dimension)
        return cls(*(np.concatenate(arrays) for arrays in zip(*(chunk._fields() for chunk in chunks), strict=True)))

    def from_frame(self, frame: int) -> _DetectionChunk:
        """The rows of ``frame`` and later (views)."""
        lo = int(np.searchsorted(self.frame, frame))
        return _DetectionChunk(*(array[lo:] for array in self._fields())) if lo else self

    def frame_arrays(self, frame: int) -> DetectionArrays:
        """The detections of ``frame`` (views on this chunk)."""
        lo, hi = np.searchsorted(self.frame, [frame, frame + 1])
        return DetectionArrays(self.boxes3d[lo:hi], self.boxes2d[lo:hi], self.scores[lo:hi], self.labels[lo:hi],
                               self.cameras[lo:hi], self.embeddings[lo:hi])


class Dataset:
    """A complete dataset folder. Open with :meth:`open`; tables load on first use."""

    def __init__(self, path: Path, manifest: dict):
        self.path = path
        self.manifest = manifest

    @classmethod
    def open(cls, path: Path | str, *, verify: bool = False) -> Dataset:
        """Open ``path``; a :class:`DatasetError` if it holds no complete manifest (e.g. an interrupted
        generation). ``verify`` also checks every file's SHA-256 against the manifest."""
        path = Path(path)
        if path.exists() and not path.is_dir():
            raise DatasetError(f"{str(path)!r} is a file, not a dataset folder (a dataset is the folder holding "
                               f"{MANIFEST_NAME})")
        if not path.is_dir():
            raise DatasetError(f"dataset folder {str(path)!r} does not exist")
        manifest = read_manifest(path)
        if manifest is None:
            inner = path / "dataset"
            hint = (f"; it looks like a 'simrig run' folder: its dataset is {str(inner)!r}"
                    if (inner / MANIFEST_NAME).is_file() else "")
            raise DatasetError(
                f"{str(path)!r} holds no complete simrig dataset ({MANIFEST_NAME} missing or not complete; "
                f"an interrupted generation leaves none){hint}"
            )
        dataset = cls(path, manifest)
        if verify:
            dataset.verify()
        return dataset

    def verify(self) -> list[str]:
        """Check that every file listed in the manifest exists and has the recorded SHA-256 (the manifest's own
        hash is checked on :meth:`open`); returns the files in the folder that the manifest does not list
        (e.g. a mosaic written by ``simrig render``), sorted, relative to the folder."""
        return self.files.verify()

    @property
    def identity(self) -> dict:
        """What tracks made on this dataset record of it (:func:`~simrig.dataset.tracks_file.write_tracks`):
        scenario name, seed and the SHA-256 of its ground-truth table. Tracks are scored only on a dataset with
        the same ground truth."""
        return {"scenario": self.scenario["name"], "seed": self.seed,
                "ground_truth_sha256": self.manifest["files"]["ground_truth"]["sha256"]}

    @cached_property
    def files(self) -> ManifestFiles:
        """The folder's files as the manifest lists them, each checked against its SHA-256 before use."""
        return ManifestFiles(self.path, self.manifest)

    # ------------------------------------------------------------------ metadata
    @property
    def seed(self) -> int:
        return int(self.manifest["seed"])

    @property
    def scenario(self) -> dict:
        """The resolved scenario the dataset was generated from (as a plain dict)."""
        return self.manifest["scenario"]

    @property
    def frame_count(self) -> int:
        return int(self.manifest["frames"])

    @property
    def source(self) -> dict | None:
        """How an imported dataset was made (``simrig import``: its ``format``, ``path``, whether it has 3D
        ground truth and a calibrated rig); ``None`` for a generated one."""
        return self.manifest.get("source")

    @property
    def has_3d(self) -> bool:
        """Whether the dataset holds world-frame 3D ground truth (an import from 2D boxes does not)."""
        source = self.source
        return source is None or bool(source.get("ground_truth_3d"))

    @property
    def has_2d(self) -> bool:
        """Whether the dataset has cameras to score 2D boxes in (an import of 3D boxes without cameras has not)."""
        return len(self.rig.cameras) > 0

    @property
    def causes_known(self) -> bool:
        """Whether the dataset records why the detector missed each box (generated: yes; imported: unknown)."""
        return self.source is None

    def source_ignored_table(self) -> pa.Table | None:
        """The boxes an imported dataset's source marks as not scored (``frame, actor_id, camera, reason``), or
        ``None`` when the manifest lists no such table."""
        if "source_ignored" not in self.manifest["files"]:
            return None
        return pq.read_table(pa.BufferReader(self.files.read("source_ignored")))

    @cached_property
    def rig(self) -> Rig:
        return rig_from_dict(json.loads(self.files.read("rig")))

    def road_markings(self) -> RoadMarkings | None:
        """The painted lines of the dataset's road (world frame), or None if it recorded none."""
        if "road" not in self.manifest["files"]:
            return None
        return RoadMarkings.from_dict(json.loads(self.files.read("road")))

    def table(self, name: str) -> pa.Table:
        """One of the Parquet tables (:data:`simrig.dataset.tables.SCHEMAS`: ``ego_poses``, ``ground_truth``,
        ``projections``, ``visibility``, ``detections``, ``sensor_truth``, ``frames``), whole, kept for the
        next call. Long runs: :meth:`columns` and :meth:`batches` read less and keep nothing."""
        if name not in self._tables:
            self._tables[name] = self.columns(name)
        return self._tables[name]

    def columns(self, name: str, columns: list[str] | None = None) -> pa.Table:
        """The ``columns`` (default: all) of table ``name``, read now and not kept (see :meth:`table`)."""
        return self._parquet(name).read(columns=columns)

    def batches(self, name: str, columns: list[str] | None = None) -> Iterator[pa.Table]:
        """Table ``name`` (its ``columns``, default all) in its row groups, in order: a long dataset's frames a
        group at a time (:data:`simrig.dataset.writer.FRAMES_PER_ROW_GROUP` frames each, as written)."""
        file = self._parquet(name)
        for group in range(file.num_row_groups):
            yield file.read_row_group(group, columns=columns)

    def has_table(self, name: str) -> bool:
        """Whether the dataset holds table ``name`` (the optional ones, ``captures`` and ``ego_estimates``, only
        when its scenario sets capture timing; ``truth_plans``, when simrig generated it since it records plans)."""
        return name in self.manifest.get("files", {})

    def num_rows(self, name: str) -> int:
        """Rows of table ``name`` (from the Parquet footer; nothing else read)."""
        return self._parquet(name).metadata.num_rows

    def _parquet(self, name: str) -> pq.ParquetFile:
        """Table ``name`` opened for reading, its file checked against the manifest's SHA-256 and its columns
        against the table's schema."""
        if name not in ALL_SCHEMAS:
            raise KeyError(f"unknown table {name!r}; tables: {', '.join(ALL_SCHEMAS)}")
        if name in OPTIONAL_SCHEMAS and not self.has_table(name):
            why = ("its scenario sets no capture timing" if name != "truth_plans"
                   else "it was imported, or generated before simrig recorded plans")
            raise KeyError(f"dataset {str(self.path)!r} has no {name} table ({why})")
        file = self.files.verified(name)
        try:
            parquet = pq.ParquetFile(file)
        except (pa.ArrowInvalid, OSError) as error:
            raise DatasetError(f"dataset {str(self.path)!r}: {name} is not a readable Parquet file ({error})") from None
        if not parquet.schema_arrow.equals(ALL_SCHEMAS[name], check_metadata=False):
            raise DatasetError(f"dataset {str(self.path)!r}: {name} columns {parquet.schema_arrow.names} do not "
                               "match its schema")
        stated = self.manifest["files"][name].get("rows")
        if stated is not None and stated != parquet.metadata.num_rows:  # a re-hashed manifest that lies
            raise DatasetError(f"dataset {str(self.path)!r}: manifest says {name} holds {stated!r} rows, its table "
                               f"holds {parquet.metadata.num_rows}")
        return parquet

    @cached_property
    def _tables(self) -> dict[str, pa.Table]:
        """Tables read whole so far (:meth:`table`)."""
        return {}

    # ------------------------------------------------------------------ records
    def _ego_rows(self) -> list[tuple[int, float, EgoPose]]:
        """(frame, timestamp [s], ego pose a tracker is given) of every frame, in order: the true pose, or the
        estimate of ``ego_estimates`` when the scenario sets an ego-pose error."""
        rows = self._pose_rows("ego_poses")
        if not self.has_table("ego_estimates"):
            return rows
        estimates = self._pose_rows("ego_estimates")
        if [row[0] for row in estimates] != [row[0] for row in rows]:
            raise DatasetError(f"dataset {str(self.path)!r}: ego_estimates does not hold one row per frame")
        return [(frame, timestamp, estimate[2]) for (frame, timestamp, _), estimate in zip(rows, estimates,
                                                                                           strict=True)]

    def _pose_rows(self, name: str) -> list[tuple[int, float, EgoPose]]:
        """(frame, timestamp [s] or NaN, pose) of every row of the pose table ``name``."""
        ego = self.columns(name)
        columns = {name: ego.column(name).to_numpy() for name in ego.column_names}
        fields = ("x", "y", "z", "yaw", "vx", "vy")
        return [
            (int(frame), float(columns["timestamp"][row]) if "timestamp" in columns else np.nan,
             EgoPose(*(float(columns[name][row]) for name in fields)))
            for row, frame in enumerate(columns["frame"])
        ]

    @cached_property
    def ground_truth(self) -> GroundTruth:
        """The whole ground truth as flat arrays (:class:`~simrig.dataset.ground_truth.GroundTruth`), read once
        per :class:`Dataset` object by the one ground-truth reader."""
        from .ground_truth import load_ground_truth

        return load_ground_truth(self)

    def ground_truth_frames(self) -> Iterator[GroundTruthFrame]:
        """Every frame's :class:`GroundTruthFrame`, in order, with per-camera projections: views on
        :attr:`ground_truth`."""
        truth = self.ground_truth
        boxes2d, truncation, occlusion, depth = truth.boxes2d, truth.truncation, truth.occlusion, load_depth(self)
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

    @property
    def image_folder(self) -> Path | None:
        """The dataset's ``images/`` folder (one PNG per camera and frame), or ``None`` without images."""
        folder = self.path / "images"
        return folder if folder.is_dir() else None

    def sensor_frames(self) -> Iterator[SensorFrame]:
        """What a tracker sees, frame by frame: a :class:`SensorFrame` per frame that was not dropped (a
        dropped frame is skipped, so the tracker sees the time jump). No ground truth is in it.

        The frames carry their detections as arrays (rows sorted by camera in rig order, as written);
        ``frame.detections`` builds :class:`~simrig.types.Detection` objects only if asked. When the dataset
        has images (generated with ``--images``), ``frame.images`` maps each camera to the path of its PNG for
        that frame (``images/CAMERA/FFFFFF.png``, RGB, the camera's width × height); empty otherwise."""
        if self.has_table("captures"):
            yield from self._delivered_sensor_frames()
            return
        dropped = self.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False)
        rig = self.rig
        images = self.image_folder
        chunks = self._detection_chunks(rig)
        window = next(chunks, None)
        for row, (frame, timestamp, pose) in enumerate(self._ego_rows()):
            # Load row groups until the window holds every row of this frame (rows are sorted by frame).
            while window is not None and (len(window.frame) == 0 or window.frame[-1] <= frame):
                following = next(chunks, None)
                if following is None:
                    break
                window = window.joined(following)
            if window is not None:
                window = window.from_frame(frame)
            if dropped[row]:
                continue
            arrays = (window.frame_arrays(frame) if window is not None
                      else _DetectionChunk.empty(self._embedding_dimension).frame_arrays(frame))
            yield SensorFrame(frame, timestamp, pose, rig, arrays=arrays, images=_image_paths(images, rig, frame))

    def _delivered_sensor_frames(self) -> Iterator[SensorFrame]:
        """:meth:`sensor_frames` of a dataset with capture timing: each detection is given at the step of the
        frame its capture arrives by (``captures.arrival_frame``), with its camera's reported capture time, and
        marked late when that is after its own frame. A capture taken in a dropped frame is lost; one arriving
        at a dropped frame is given at the next frame that is stepped. Reads the detections whole."""
        dropped = self.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False)
        rig = self.rig
        frames = len(dropped)
        detections = _DetectionChunk.concatenated(list(self._detection_chunks(rig)), self._embedding_dimension)
        captures = self._captures()
        stepped = np.flatnonzero(~dropped)
        # the first stepped frame at or after each frame (frames: never)
        next_step = np.append(stepped, frames)[np.searchsorted(stepped, np.arange(frames + 1))]
        rows = detections.frame.astype(np.int64) * len(rig.cameras) + detections.cameras
        arrival = next_step[np.minimum(captures["arrival_frame"][rows], frames)]
        arrival[dropped[detections.frame]] = frames
        reported = captures["reported_time"][rows]
        order = np.lexsort((np.arange(len(rows)), detections.cameras, arrival))
        arrival = arrival[order]
        images = self.image_folder
        for frame, timestamp, pose in self._ego_rows():
            if dropped[frame]:
                continue
            lo, hi = np.searchsorted(arrival, [frame, frame + 1])
            take = order[lo:hi]
            arrays = DetectionArrays(detections.boxes3d[take], detections.boxes2d[take], detections.scores[take],
                                     detections.labels[take], detections.cameras[take], detections.embeddings[take],
                                     reported[take], detections.frame[take] < frame)
            yield SensorFrame(frame, timestamp, pose, rig, arrays=arrays, images=_image_paths(images, rig, frame))

    @cached_property
    def _embedding_dimension(self) -> int:
        """The length of the detections' embeddings (0: none), over the whole table (one column read)."""
        dimension = 0
        for group in self.batches("detections", ["embedding"]):
            lengths = pc.list_value_length(group.column("embedding")).to_numpy(zero_copy_only=False)
            dimension = max(dimension, int(lengths.max(initial=0)))
        return dimension

    def _detection_chunks(self, rig: Rig) -> Iterator[_DetectionChunk]:
        """The detections table a row group at a time, as the arrays a tracker is given."""
        dimension = self._embedding_dimension
        for table in self.batches("detections"):
            yield _DetectionChunk.of_table(table, rig, dimension, f"{self.path}: detections")

    def _captures(self) -> dict[str, np.ndarray]:
        """The ``captures`` table as arrays indexed by ``frame × C + camera`` (rig order), checked to hold one row
        per frame and camera in that order."""
        table = self.columns("captures")
        c = len(self.rig.cameras)
        codes = {name: code for code, name in enumerate(self.rig.camera_names)}
        key = (table.column("frame").to_numpy().astype(np.int64) * c
               + string_codes(table.column("camera"), codes, f"{self.path}: captures camera"))
        if not np.array_equal(key, np.arange(self.frame_count * c)):
            raise DatasetError(f"dataset {str(self.path)!r}: captures does not hold one row per frame and camera")
        return {"capture_time": table.column("capture_time").to_numpy(),
                "reported_time": table.column("reported_time").to_numpy(),
                "arrival_frame": table.column("arrival_frame").to_numpy().astype(np.int64),
                "fired": table.column("fired").to_numpy(zero_copy_only=False)}

    def _timing_summary(self) -> list[str]:
        """The ``timing`` line of :meth:`summary` for a dataset with capture timing (none otherwise): the spread
        of the capture times, how many detections arrive late or never, the ego-pose error."""
        parts = []
        if self.has_table("captures"):
            captures = self._captures()
            c = len(self.rig.cameras)
            fired = captures["fired"]
            offset = (captures["capture_time"] - np.repeat(np.arange(self.frame_count), c)
                      / float(self.scenario["frame_rate_hz"]))[fired]
            detections = self.columns("detections", ["frame", "camera"])
            captured = detections.column("frame").to_numpy().astype(np.int64)
            codes = {name: code for code, name in enumerate(self.rig.camera_names)}
            when = captures["arrival_frame"][captured * c + string_codes(detections.column("camera"), codes,
                                                                          f"{self.path}: detections camera")]
            late = int((when > captured).sum())
            never = int((when >= self.frame_count).sum())
            parts.append(f"captures {1000 * offset.min():+.0f} to {1000 * offset.max():+.0f} ms after the tick"
                         f"{'' if fired.all() else f', {int((~fired).sum())} camera-frames without an image'}; "
                         f"{late} of {len(when)} detections late, {never} after the last frame")
        if self.has_table("ego_estimates"):
            true, given = self.columns("ego_poses"), self.columns("ego_estimates")
            error = np.hypot(*(given.column(axis).to_numpy() - true.column(axis).to_numpy() for axis in "xy"))
            parts.append(f"ego pose estimated (position error up to {error.max():.2f} m)")
        return [f"timing    {'; '.join(parts)}"] if parts else []

    def summary_counts(self) -> dict[str, int | float]:
        """What :meth:`summary` reports, as numbers: ``actors`` (distinct), ``actors_per_frame_min``/``_max``/
        ``_mean``, ``truth_rows``, ``projection_rows``, ``in_view_pairs`` (actor-camera pairs in view),
        ``detections``, ``false_positives`` (clutter), ``missed_pairs`` (pairs in view with no detection),
        ``dropped_frames``; and per class the distinct actors under ``class_counts`` (a dict)."""
        truth = self.columns("ground_truth", ["frame", "actor_id", "class"])
        ids = truth.column("actor_id").to_numpy()
        class_counts = {}
        unique_ids, first = np.unique(ids, return_index=True)
        if len(truth):
            first_classes = np.asarray(truth.column("class").take(first).to_pylist(), dtype=object)
            names, counts = np.unique(first_classes.astype(str), return_counts=True)
            class_counts = dict(zip(names.tolist(), counts.tolist(), strict=True))
        per_frame = np.bincount(truth.column("frame").to_numpy(), minlength=self.frame_count)
        truth_rows = len(truth)
        del truth
        projection_rows, in_view_pairs = 0, 0
        for group in self.batches("projections", ["in_view"]):
            projection_rows += len(group)
            in_view_pairs += int(group.column("in_view").to_numpy(zero_copy_only=False).sum())
        clutter, delivered = 0, 0
        for group in self.batches("sensor_truth", ["actor_id", "detection"]):
            truth_actor = group.column("actor_id").to_numpy()
            clutter += int(np.sum(truth_actor < 0))
            delivered += int(np.sum((truth_actor >= 0) & (group.column("detection").to_numpy() >= 0)))
        dropped = int(self.columns("frames", ["dropped"]).column("dropped").to_numpy(zero_copy_only=False).sum())
        return {
            "actors": len(unique_ids), "class_counts": class_counts,
            "actors_per_frame_min": int(per_frame.min()), "actors_per_frame_max": int(per_frame.max()),
            "actors_per_frame_mean": float(per_frame.mean()), "truth_rows": truth_rows,
            "projection_rows": projection_rows, "in_view_pairs": in_view_pairs,
            "detections": self.num_rows("detections"), "false_positives": clutter,
            "missed_pairs": in_view_pairs - delivered, "dropped_frames": dropped,
        }

    def summary(self) -> str:
        """A few readable lines: scenario, seed, frames, actors, rig, rows, events, capture timing."""
        counts = self.summary_counts()
        class_counts = counts["class_counts"]
        scenario = self.scenario
        event_text = ", ".join(f"{event['event']} at frame {event['frame']}" for event in self.manifest["events"])
        lines = [
            f"dataset   {self.path}",
            f"scenario  {scenario['name']} ({scenario['traffic']['env']}), seed {self.seed}",
            f"frames    {self.frame_count} at {scenario['frame_rate_hz']:g} Hz "
            f"({self.frame_count / scenario['frame_rate_hz']:.1f} s)",
            f"actors    {counts['actors']} distinct "
            f"({', '.join(f'{k} {v}' for k, v in class_counts.items()) or 'none'}); "
            f"{counts['actors_per_frame_min']}–{counts['actors_per_frame_max']} per frame, "
            f"mean {counts['actors_per_frame_mean']:.1f}",
            f"rig       {self.rig.name}: {', '.join(self.rig.camera_names) or 'no cameras (3D only)'}",
            f"rows      ground_truth {counts['truth_rows']}, projections {counts['projection_rows']} "
            f"({counts['in_view_pairs']} in view)",
            (f"sensor    {counts['detections']} detections ({counts['false_positives']} false positives), "
             f"{counts['missed_pairs']} actor-camera pairs in view missed; {counts['dropped_frames']} frames dropped; "
             f"visibility {self.manifest.get('visibility', 'not measured')}") if self.source is None
            else "sensor    none (an imported dataset holds ground truth only)",
            f"events    {event_text or 'none'}",
            *self._timing_summary(),
        ]
        source = self.source
        if source is not None:
            lines.append(f"source    imported from {source['format']} ({source['path']}): "
                         f"{'3D and 2D' if self.has_3d and self.has_2d else '3D only' if self.has_3d else '2D only'}"
                         f" ground truth; rig {'calibrated' if source.get('calibrated_rig') else 'unknown'}; "
                         "no detections, error causes unknown")
        return "\n".join(lines)
