"""KITTI tracking labels → a 2D-only dataset, one camera per sequence.

Where the label files are: ``SRC/CAMERA/label_02/0000.txt`` (``simrig export --format kitti``: the folder names
the camera), ``SRC/label_02/NNNN.txt`` or a ``label_02`` folder itself (KITTI's layout: each sequence a camera
named by its number), or one ``.txt`` file. A line is ``frame track_id type truncated occluded alpha left top
right bottom height width length x y z rotation_y [score]`` (space-separated, 0-based frames, pixel boxes); every
line of a file has as many fields as its first, 17 or 18 (:mod:`simrig.formats.kitti.tracks` reads tracker files
the same way).

Only the pixel box is imported (the 3D fields are in a KITTI camera frame whose calibration the labels do not
carry). Types map to classes as the KITTI tracks reader maps them — ``Car`` → car, ``Truck`` → truck, ``Misc`` →
bus, ``Cyclist`` → motorcycle (``simrig export`` writes a motorcycle as ``Cyclist``), ``Pedestrian`` →
pedestrian — so that ground truth and a tracker's files in the same format meet in the same class. Marked as not
scored (:attr:`~simrig.formats.evaluation.IgnoreRule.SOURCE`, as KITTI's benchmark treats them): ``Van`` (class
car) and ``Person_sitting`` (class pedestrian), KITTI's distractors of those classes, and every ``DontCare``
region — once for each class of its sequence, since a region applies to every class. simrig removes the tracker
boxes matched (IoU ≥ 0.5) to such a box, where TrackEval's KITTI reader removes those mostly inside a
``DontCare`` region; its other KITTI rules (minimum height, truncation and occlusion levels) are not applied,
so ``simrig score`` on the import gives TrackEval's numbers on the MOTChallenge export, not on KITTI files.
Other types (``Tram``, ``Misc`` aside) and rows with id −1 other than ``DontCare`` are left out and counted in
``source.left_out_rows``.

Image size: the sequence's first image (``image_02/NNNN/000000.png`` beside ``label_02``) when present, else
KITTI's 1242 × 375 px, enlarged to hold every box. Frame rate: 10 Hz (KITTI's). Object ids are per sequence:
actor id = sequence number × :data:`~simrig.formats.imported_truth.ID_STRIDE` + id; ``DontCare`` regions get ids from
:data:`~simrig.formats.imported_truth.ID_STRIDE` / 2 up.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simrig.formats.imported_truth import (
    ID_STRIDE,
    MAX_IMPORTED_FRAMES,
    ImportedTruth,
    SourceError,
    check_unique,
    uncalibrated_camera,
)
from simrig.formats.kitti.tracks import CLASS_OF_TYPE, FIELDS, GROUND_TRUTH_FOLDER
from simrig.formats.text_rows import integer, number, parse_lines
from simrig.types import Rig

FRAME_RATE_HZ = 10.0
KITTI_IMAGE_SIZE = (1242, 375)
"""[px] width, height of KITTI's colour camera images."""
DISTRACTOR_TYPES = {"Van": "car", "Person_sitting": "pedestrian"}
"""KITTI's distractor types and the class whose ground truth they are marked in."""
DONT_CARE = "DontCare"
IMPORT_EVALUATION = {"ignore": True, "min_height_px": 0.0, "min_visible_fraction": 0.0, "max_truncation": 1.0,
                     "classes": "each"}


def label_files(src: Path) -> list[tuple[str, Path]]:
    """(camera name, label file) of every sequence at ``src`` (see the module docstring's layouts)."""
    if src.is_file():
        return [(src.stem, src)]
    exported = sorted(p for p in src.iterdir() if (p / GROUND_TRUTH_FOLDER).is_dir()) if src.is_dir() else []
    if exported and src.name != GROUND_TRUTH_FOLDER and not (src / GROUND_TRUTH_FOLDER).is_dir():
        out = []
        for folder in exported:
            files = sorted((folder / GROUND_TRUTH_FOLDER).glob("*.txt"))
            out += [(folder.name if len(files) == 1 else f"{folder.name}-{f.stem}", f) for f in files]
        return out
    folder = src / GROUND_TRUTH_FOLDER if (src / GROUND_TRUTH_FOLDER).is_dir() else src
    files = sorted(folder.glob("*.txt"))
    if not files:
        raise SourceError(f"{src}: no KITTI label file (label_02/NNNN.txt, CAMERA/label_02/0000.txt or a .txt)")
    return [(f.stem, f) for f in files]


def _image_size(file: Path, extent: np.ndarray) -> tuple[int, int]:
    image = file.parent.parent / "image_02" / file.stem / "000000.png"
    if image.is_file():
        from PIL import Image

        with Image.open(image) as handle:
            return handle.size
    return (max(KITTI_IMAGE_SIZE[0], int(np.ceil(extent[0]))), max(KITTI_IMAGE_SIZE[1], int(np.ceil(extent[1]))))


def read_kitti_truth(src: Path) -> ImportedTruth:
    """The ground truth of the KITTI label files at ``src`` (see the module docstring)."""
    sequences = label_files(src)
    cameras: dict[str, tuple[int, int]] = {}
    columns: dict[str, list] = {key: [] for key in ("frame", "actor", "camera", "label", "box", "reason")}
    left_out = 0
    for k, (camera, file) in enumerate(sequences):
        rows, regions = [], []
        for line, fields in parse_lines(file, None, 17, FIELDS):
            if len(fields) > 18:
                raise SourceError(f"{file}:{line}: {len(fields)} fields where 17 or 18 are expected")
            for column in (c for c in range(len(fields)) if c != 2):
                number(file, line, fields, column, FIELDS)  # every numeric field must be a number
            frame, track = integer(file, line, fields, 0, FIELDS), integer(file, line, fields, 1, FIELDS)
            if not 0 <= frame < MAX_IMPORTED_FRAMES:
                raise SourceError(f"{file}:{line}: frame {frame} is outside 0 … {MAX_IMPORTED_FRAMES - 1:,} (KITTI "
                                  "frames start at 0)")
            left, top, right, bottom = (number(file, line, fields, c, FIELDS) for c in range(6, 10))
            if right <= left or bottom <= top:
                raise SourceError(f"{file}:{line}: empty box {[left, top, right, bottom]} (needs right > left and "
                                  "bottom > top)")
            kind = fields[2]
            if kind == DONT_CARE:
                regions.append((frame, (left, top, right, bottom)))
                continue
            label = DISTRACTOR_TYPES.get(kind) or CLASS_OF_TYPE.get(kind)
            if label is None or track < 0 or track >= ID_STRIDE // 2:
                left_out += 1
                continue
            reason = f"{kind} (KITTI distractor of {label})" if kind in DISTRACTOR_TYPES else ""
            rows.append((frame, k * ID_STRIDE + track, label, (left, top, right, bottom), reason))
        labels = sorted({r[2] for r in rows}) or ["car"]
        for j, (frame, box) in enumerate(regions):
            for m, label in enumerate(labels):
                rows.append((frame, k * ID_STRIDE + ID_STRIDE // 2 + j * len(labels) + m, label, box, DONT_CARE))
        extent = np.array([[r[3][2], r[3][3]] for r in rows]).reshape(-1, 2).max(axis=0, initial=1.0)
        cameras[camera] = _image_size(file, extent)
        for frame, actor, label, box, reason in rows:
            columns["frame"].append(frame)
            columns["actor"].append(actor)
            columns["camera"].append(camera)
            columns["label"].append(label)
            columns["box"].append(box)
            columns["reason"].append(reason)
    if not columns["frame"]:
        raise SourceError(f"{src}: the label files hold no box to import")
    rig = Rig("imported", tuple(uncalibrated_camera(name, *size) for name, size in cameras.items()))
    frame = np.array(columns["frame"], dtype=np.int64)
    actor = np.array(columns["actor"], dtype=np.int64)
    order = np.lexsort((actor, frame))
    frames = int(frame.max()) + 1
    n, c = len(order), len(rig.cameras)
    camera_index = np.array([rig.camera_names.index(name) for name in columns["camera"]], dtype=np.int64)[order]
    boxes2d = np.full((n, c, 4), np.nan)
    boxes2d[np.arange(n), camera_index] = np.array(columns["box"], dtype=float).reshape(-1, 4)[order]
    in_view = np.zeros((n, c), dtype=bool)
    in_view[np.arange(n), camera_index] = True
    reasons = np.array(columns["reason"], dtype=object)[order]
    truth = ImportedTruth(
        name="kitti-import", frame_rate_hz=FRAME_RATE_HZ, rig=rig, timestamps=np.arange(frames) / FRAME_RATE_HZ,
        egos=np.zeros((frames, 6)), frame=frame[order], actor_id=actor[order],
        label=np.array(columns["label"], dtype=object)[order], boxes=np.full((n, 9), np.nan), boxes2d=boxes2d,
        in_view=in_view, occlusion=np.full((n, c), np.nan), ignored=in_view * (reasons != "")[:, None].astype(np.int8),
        reasons=reasons, evaluation=IMPORT_EVALUATION,
        source={"format": "kitti", "path": str(src), "ground_truth_3d": False, "calibrated_rig": False,
                "causes": "unknown", "sequences": {camera: str(file) for camera, file in sequences},
                "id_stride": ID_STRIDE, "left_out_rows": left_out},
    )
    check_unique(truth, str(src))
    return truth
