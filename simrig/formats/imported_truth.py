"""One imported dataset, whatever its source: ground truth as flat arrays, written with the dataset writer.

Every format's ``ground_truth`` module (:mod:`simrig.formats.motchallenge`, :mod:`simrig.formats.kitti`,
:mod:`simrig.formats.nuscenes`) turns its files into an :class:`ImportedTruth` and hands it to
:func:`write_imported`, which writes the same seven tables a generated
dataset has through :class:`~simrig.dataset.writer.DatasetWriter` (partial folder, manifest last, published by
one rename: an interrupted import leaves nothing that looks complete). What the source lacks is marked, not
invented:

- no 3D boxes (MOTChallenge, KITTI labels read as 2D): the world boxes are NaN and the manifest's
  ``source.ground_truth_3d`` is false, so ``simrig score`` prints no 3D numbers;
- no calibration: each camera (one per sequence) has the image size of its sequence and nominal intrinsics, and
  ``source.calibrated_rig`` is false (nothing is projected through it);
- no cameras (a nuScenes import): a rig with none, and only 3D is scored;
- no sensor: the ``detections`` and ``sensor_truth`` tables are empty, and every error's cause is ``unknown``;
- no visibility or truncation measured: occlusion NaN, visible pixels −1 (not rendered), truncation 0.

Boxes the source marks as not scored are in ``source_ignored.parquet`` (``frame, actor_id, camera, kind,
reason``): ``kind`` ``distractor`` (distractor classes, ``DontCare``; read as the
:attr:`~simrig.formats.evaluation.IgnoreRule.SOURCE` rule: a tracker box matched to one is removed) or
``unevaluated`` (ground truth the benchmark does not evaluate; the ``UNEVALUATED`` rule: a tracker box matched
to one stays a false positive).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from simrig.dataset.ground_truth import SOURCE_KINDS
from simrig.dataset.manifest import package_versions
from simrig.dataset.writer import DatasetWriter
from simrig.errors import DatasetError, SimrigError
from simrig.rig import rig_to_dict
from simrig.types import Camera, Rig

ID_STRIDE = 1_000_000_000
"""Actor id = sequence number × this + the sequence's own id (MOTChallenge and KITTI ids are per sequence)."""
MAX_IMPORTED_FRAMES = 1_000_000
"""The most frames an imported sequence may span (a generated scenario's bound too)."""
SEED = 0
"""An imported dataset has no random streams; its manifest's ``seed`` is 0."""
SOURCE_IGNORED_FILE = "source_ignored.parquet"
SOURCE_IGNORED = pa.schema([pa.field("frame", pa.int32()), pa.field("actor_id", pa.int64()),
                            pa.field("camera", pa.string()), pa.field("kind", pa.string()),
                            pa.field("reason", pa.string())])
SAMPLE_TOKENS_FILE = "sample_tokens.json"


class SourceError(SimrigError):
    """Source files that cannot be imported; the message names the file and line."""


def uncalibrated_camera(name: str, width: int, height: int) -> Camera:
    """A camera of an imported 2D sequence: its image size [px]; nominal intrinsics (focal length = width, the
    principal point at the centre) and mount (at the ego origin, looking ahead), which nothing projects through:
    the dataset's manifest says the rig is not calibrated."""
    return Camera(name=name, width=int(width), height=int(height), fx=float(width), fy=float(width),
                  cx=width / 2.0, cy=height / 2.0, position=(0.0, 0.0, 0.0), yaw=0.0)


@dataclass(frozen=True, eq=False)
class ImportedTruth:
    """Ground truth read from a source, rows sorted by frame.

    name: the dataset's scenario name; frame_rate_hz [Hz]; timestamps ``(F,)`` [s]; egos ``(F, 6)`` world-frame
    ego pose ``x, y, z`` [m], ``yaw`` [rad], ``vx, vy`` [m/s] (zeros when the source has none). Rows: frame,
    actor_id, label ``(R,)``; boxes ``(R, 9)`` world boxes (NaN without 3D); per camera ``(R, C)``: boxes2d
    ``(R, C, 4)`` pixel boxes (NaN where not in view), in_view, occlusion (NaN: unknown), ignored (what the
    source marks the box as: 0 nothing, 1 + an index into :data:`~simrig.dataset.ground_truth.SOURCE_KINDS`) with
    ``reasons`` ``(R,)`` why. ``evaluation``: the dataset's ``[evaluation]``
    table (the source benchmark's protocol); ``source``: the manifest's description of the source;
    ``tokens``/``scenes``: a nuScenes import's sample token per frame and scenes.
    """

    name: str
    frame_rate_hz: float
    rig: Rig
    timestamps: np.ndarray
    egos: np.ndarray
    frame: np.ndarray
    actor_id: np.ndarray
    label: np.ndarray
    boxes: np.ndarray
    boxes2d: np.ndarray
    in_view: np.ndarray
    occlusion: np.ndarray
    ignored: np.ndarray
    reasons: np.ndarray
    evaluation: dict
    source: dict
    tokens: list[str] | None = None
    scenes: list[dict] | None = None


def _frame_columns(truth: ImportedTruth, position: int, lo: int, hi: int) -> dict[str, dict]:
    """The column arrays of one frame (rows ``lo:hi``) for every table; per-camera rows actor-major."""
    n, c = hi - lo, len(truth.rig.cameras)
    frame = int(position)
    names = np.array(truth.rig.camera_names, dtype=object)
    boxes2d = truth.boxes2d[lo:hi].reshape(n * c, 4)
    pairs = {"frame": np.full(n * c, frame, dtype=np.int32), "actor_id": np.repeat(truth.actor_id[lo:hi], c),
             "camera": np.tile(names, n).astype(str) if c else np.zeros(0, dtype=str)}
    in_view = truth.in_view[lo:hi].reshape(-1)
    empty_f64 = np.zeros(0)
    return {
        "ego_poses": {"frame": np.array([frame], dtype=np.int32), "timestamp": truth.timestamps[[position]],
                      **{key: truth.egos[[position], k] for k, key in enumerate(("x", "y", "z", "yaw", "vx", "vy"))}},
        "ground_truth": {"frame": np.full(n, frame, dtype=np.int32), "actor_id": truth.actor_id[lo:hi],
                         "class": truth.label[lo:hi].astype(str),
                         **{key: truth.boxes[lo:hi, k] for k, key in enumerate(
                             ("x", "y", "z", "length", "width", "height", "yaw", "vx", "vy"))}},
        "projections": {**pairs, **{key: boxes2d[:, k] for k, key in enumerate(("x1", "y1", "x2", "y2"))},
                        "truncation": np.where(in_view, 0.0, np.nan), "depth": np.full(n * c, np.nan),
                        "in_view": in_view},
        "visibility": {**pairs, "visible_px": np.full(n * c, -1, dtype=np.int32),
                       "silhouette_px": np.full(n * c, -1, dtype=np.int32),
                       "occlusion": truth.occlusion[lo:hi].reshape(-1)},
        "detections": {"frame": np.zeros(0, dtype=np.int32), "camera": np.zeros(0, dtype=str),
                       "index": np.zeros(0, dtype=np.int32),
                       **{key: empty_f64 for key in ("x1", "y1", "x2", "y2", "score")},
                       "label": np.zeros(0, dtype=str),
                       **{key: empty_f64 for key in ("x", "y", "z", "length", "width", "height", "yaw", "vx", "vy")},
                       "embedding": pa.array([], type=pa.list_(pa.float32()))},
        "sensor_truth": {"frame": np.zeros(0, dtype=np.int32), "camera": np.zeros(0, dtype=str),
                         "actor_id": np.zeros(0, dtype=np.int64), "detection": np.zeros(0, dtype=np.int32),
                         "probability": empty_f64, "causes": pa.array([], type=pa.list_(pa.string()))},
        "frames": {"frame": np.array([frame], dtype=np.int32), "timestamp": truth.timestamps[[position]],
                   "dropped": np.array([False]), "events": pa.array([[]], type=pa.list_(pa.string()))},
    }


def check_unique(truth: ImportedTruth, what: str) -> None:
    """A :class:`SourceError` if an actor id appears twice in one frame (the source's ids are reused)."""
    key = np.column_stack([truth.frame, truth.actor_id])
    if len(key) < 2:
        return
    order = np.lexsort((truth.actor_id, truth.frame))
    same = np.nonzero(np.all(key[order][1:] == key[order][:-1], axis=1))[0]
    if len(same):
        f, a = key[order][same[0]]
        raise SourceError(f"{what}: object {a} appears twice in frame {f}")


def write_imported(truth: ImportedTruth, out: Path | str, *, overwrite: bool = False) -> dict:
    """Write ``truth`` as a complete dataset folder ``out`` (refused if it holds a dataset and not
    ``overwrite``, or anything else); returns the manifest."""
    frames = len(truth.timestamps)
    if frames < 1:
        raise DatasetError(f"{truth.source.get('path')}: the source holds no frame to import")
    bounds = np.searchsorted(truth.frame, np.arange(frames + 1))
    scenario = {
        "name": truth.name,
        "description": f"imported from {truth.source['format']}: {truth.source['path']}",
        "frame_rate_hz": float(truth.frame_rate_hz),
        "frames": frames,
        "traffic": {"env": f"imported ({truth.source['format']})"},
        "evaluation": truth.evaluation,
    }
    with DatasetWriter(out, overwrite=overwrite) as writer:
        for position in range(frames):
            writer.write_frame(_frame_columns(truth, position, int(bounds[position]), int(bounds[position + 1])))
        writer.write_json("rig.json", rig_to_dict(truth.rig))
        rows, cams = np.nonzero(truth.ignored)
        if len(rows):
            kinds = np.array(SOURCE_KINDS, dtype=object)[truth.ignored[rows, cams].astype(int) - 1]
            table = pa.table({"frame": truth.frame[rows].astype(np.int32), "actor_id": truth.actor_id[rows],
                              "camera": np.array(truth.rig.camera_names, dtype=object)[cams].astype(str),
                              "kind": kinds.astype(str), "reason": truth.reasons[rows].astype(str)},
                             schema=SOURCE_IGNORED)
            pq.write_table(table, writer.partial / SOURCE_IGNORED_FILE)
        if truth.tokens is not None:
            writer.write_json(SAMPLE_TOKENS_FILE, {"tokens": list(truth.tokens), "scenes": truth.scenes or []})
        return writer.commit({"scenario": scenario, "seed": SEED, "frames": frames, "visibility": "not measured",
                              "versions": package_versions(), "events": [], "source": truth.source})
