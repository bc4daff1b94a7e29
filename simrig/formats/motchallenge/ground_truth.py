"""MOTChallenge ground truth → a 2D-only dataset, one camera per sequence.

Where the sequences are (the first layout that fits):

- TrackEval's layout (also ``simrig export --format motchallenge``): ``SRC/gt/mot_challenge/BENCH-SPLIT/SEQ/``,
  the sequences listed in ``SRC/gt/mot_challenge/seqmaps/BENCH-SPLIT.txt`` when it exists (one benchmark
  folder, or name it: ``SRC/gt/mot_challenge/BENCH-SPLIT``);
- a benchmark folder as downloaded (``MOT17/train``): every ``SEQ/gt/gt.txt`` under it;
- one sequence folder (``SEQ/gt/gt.txt``).

Each sequence's ``seqinfo.ini`` gives its length, frame rate and image size (without it: the last frame of its
ground truth, 30 Hz, and the boxes' extent). The dataset's frames are 0-based (MOTChallenge frame 1 is frame 0)
and as many as the longest sequence; its frame rate is the first sequence's.

Rows are ``frame, id, left, top, width, height, consider[, class, visibility, …]`` (pixels; every line with as
many columns as the file's first, at least 7; without a class column every row is a pedestrian, where
TrackEval refuses such ground truth). What the import does with them follows TrackEval's
``MotChallenge2DBox`` preprocessing (TrackEval 1.3, ``get_preprocessed_seq_data``), which it reproduces when
scored:

- class 1 (``pedestrian``; every row when the file has no class column) with ``consider`` ≠ 0: ground truth
  of class ``pedestrian``;
- the distractor classes — 2 ``person_on_vehicle``, 7 ``static_person``, 8 ``distractor``, 12 ``reflection``
  (and 6 ``non_mot_vehicle`` in a ``MOT20`` benchmark) — whatever their ``consider`` flag: boxes marked as not
  scored (:attr:`~simrig.formats.evaluation.IgnoreRule.SOURCE`): a tracker box matched to one (Hungarian on
  IoU ≥ 0.5) is removed, and the box is no miss;
- every other row (other classes — cars, occluders … — and pedestrians whose ``consider``, read as an integer
  as TrackEval reads it, is 0): boxes marked as ground truth the benchmark does not evaluate
  (:attr:`~simrig.formats.evaluation.IgnoreRule.UNEVALUATED`): they take part in the match above like every
  box, so they can take a tracker box away from a distractor, but a tracker box matched to one is kept (a
  false positive), and the box is no miss — TrackEval's rule exactly.

A sequence named ``CAMERA-CLASS`` with a simrig class (``simrig export``'s layout, one sequence per camera and
class) becomes rows of that class in camera ``CAMERA``; any other sequence is a camera of its own name. The
MOTChallenge visibility column is not kept (TrackEval does not use it; a box with visibility 0 is scored).
Object ids are per sequence: actor id = sequence number × :data:`~simrig.formats.imported_truth.ID_STRIDE` +
the sequence's id. The dataset scores class-agnostic (``classes = "any"``, MOTChallenge's protocol) unless every
sequence names its class, and ignores nothing but the source's distractors.
"""

from __future__ import annotations

import configparser
from pathlib import Path

import numpy as np

from simrig.dataset.tracks_file import CLASSES
from simrig.formats.imported_truth import (
    ID_STRIDE,
    MAX_IMPORTED_FRAMES,
    ImportedTruth,
    SourceError,
    check_unique,
    uncalibrated_camera,
)
from simrig.formats.motchallenge.tracks import ANY
from simrig.formats.text_rows import numbers, parse_lines
from simrig.reading import read_capped
from simrig.types import ActorClass, Rig

PEDESTRIAN_CLASS = 1
CLASS_NAMES = {1: "pedestrian", 2: "person_on_vehicle", 3: "car", 4: "bicycle", 5: "motorbike", 6: "non_mot_vehicle",
               7: "static_person", 8: "distractor", 9: "occluder", 10: "occluder_on_ground", 11: "occluder_full",
               12: "reflection", 13: "crowd"}
"""MOTChallenge's class ids (TrackEval's ``class_name_to_class_id``)."""
DISTRACTOR_CLASSES = (2, 7, 8, 12)
MOT20_DISTRACTOR_CLASSES = (*DISTRACTOR_CLASSES, 6)
DISTRACTOR, UNEVALUATED = 1, 2
"""What the source marks a row as: 1 + the index of the kind in :data:`~simrig.dataset.ground_truth.SOURCE_KINDS`."""
COLUMNS = ("frame", "id", "left", "top", "width", "height", "consider", "class", "visibility")
DEFAULT_FRAME_RATE_HZ = 30.0
IMPORT_EVALUATION = {"ignore": True, "min_height_px": 0.0, "min_visible_fraction": 0.0, "max_truncation": 1.0}
"""The imported dataset's ``[evaluation]``: only the source's own marks (range has no effect without 3D)."""


def _sequence_folders(src: Path) -> tuple[str, list[Path]]:
    """(benchmark name, the sequence folders) at ``src`` (see the module docstring's layouts)."""
    if (src / "gt" / "gt.txt").is_file():
        return src.parent.name, [src]
    root = src / "gt" / "mot_challenge"
    if root.is_dir():
        benchmarks = sorted(p for p in root.iterdir() if p.is_dir() and p.name != "seqmaps")
        if len(benchmarks) != 1:
            raise SourceError(f"{root}: holds {len(benchmarks)} benchmark folders "
                              f"({', '.join(p.name for p in benchmarks) or 'none'}); import one of them")
        src = benchmarks[0]
    seqmap = src.parent / "seqmaps" / f"{src.name}.txt"
    if seqmap.is_file():
        text = read_capped(seqmap, "seqmap", SourceError).decode("utf-8", errors="replace")
        names = [line.strip() for line in text.splitlines()[1:] if line.strip()]
        folders = [src / name for name in names]
        for folder in folders:
            if not (folder / "gt" / "gt.txt").is_file():
                raise SourceError(f"{seqmap}: sequence {folder.name!r} has no {folder / 'gt' / 'gt.txt'}")
    else:
        folders = sorted(p for p in src.iterdir() if (p / "gt" / "gt.txt").is_file()) if src.is_dir() else []
    if not folders:
        raise SourceError(f"{src}: no MOTChallenge sequence (SEQ/gt/gt.txt) found")
    return src.name, folders


SEQINFO_BOUNDS = {"seqLength": (1, 1_000_000), "frameRate": (0.1, 100), "imWidth": (1, 65_536), "imHeight": (1, 65_536)}
"""What a seqinfo.ini value may be (frames, Hz, px): a dataset of simrig's own has the same bounds."""


def _seqinfo(folder: Path) -> dict:
    path = folder / "seqinfo.ini"
    if not path.is_file():
        return {}
    parser = configparser.ConfigParser()
    try:
        parser.read_string(read_capped(path, "seqinfo.ini", SourceError).decode("utf-8"))
        section = parser["Sequence"]
        info = {key: float(section[key]) for key in ("seqLength", "frameRate", "imWidth", "imHeight") if key in section}
    except (configparser.Error, KeyError, ValueError) as error:
        reason = " ".join(str(error).split())  # configparser's text spans lines
        raise SourceError(f"{path}: not a MOTChallenge seqinfo.ini ({reason})") from None
    for key, (low, high) in SEQINFO_BOUNDS.items():
        if key in info and not low <= info[key] <= high:
            raise SourceError(f"{path}: {key} {info[key]:g} is outside {low:g} … {high:g}")
    return info


def _camera_and_label(name: str) -> tuple[str, str | None]:
    """(camera, class or ``None``) of a sequence name: ``CAMERA-CLASS`` with a simrig class, else the name."""
    camera, _, label = name.rpartition("-")
    if camera and label in CLASSES:
        return camera, label
    if camera and label == ANY:
        return camera, None
    return name, None


def _read_sequence(folder: Path, distractors: tuple[int, ...]) -> dict:
    """The rows of one sequence's ``gt/gt.txt``: frame (0-based), id, box, what the source marks it as (0: scored
    ground truth, :data:`DISTRACTOR`, :data:`UNEVALUATED`) and why."""
    file = folder / "gt" / "gt.txt"
    rows = []
    lines = parse_lines(file, ",", 7, COLUMNS)
    has_kind = bool(lines) and len(lines[0][1]) >= 8
    columns, integers = ((*range(8),), (0, 1, 7)) if has_kind else ((*range(7),), (0, 1))
    values = numbers(file, lines, columns, COLUMNS, integers=integers)
    for (line, fields), row in zip(lines, values.tolist(), strict=True):
        frame = int(row[0]) - 1
        if not 0 <= frame < MAX_IMPORTED_FRAMES:
            raise SourceError(f"{file}:{line}: frame {frame + 1} is outside 1 … {MAX_IMPORTED_FRAMES:,} (MOTChallenge "
                              "frames start at 1)")
        ident = int(row[1])
        if not 0 <= ident < ID_STRIDE:
            raise SourceError(f"{file}:{line}: id {ident} outside 0…{ID_STRIDE - 1}")
        left, top, width, height, consider = row[2:7]
        if width <= 0 or height <= 0:
            raise SourceError(f"{file}:{line}: box width {fields[4]} and height {fields[5]} must be positive")
        kind = int(row[7]) if has_kind else PEDESTRIAN_CLASS
        name = f"class {kind} ({CLASS_NAMES.get(kind, 'unknown')})"
        if kind in distractors:
            mark, reason = DISTRACTOR, name
        elif kind == PEDESTRIAN_CLASS and int(consider) != 0:  # TrackEval reads the flag as an integer
            mark, reason = 0, ""
        else:
            mark, reason = UNEVALUATED, f"{name}, consider {fields[6]}"
        rows.append((frame, ident, left, top, left + width, top + height, mark, reason))
    return {"rows": rows, "file": file}


def read_motchallenge_truth(src: Path) -> ImportedTruth:
    """The ground truth of the MOTChallenge sequences at ``src`` (see the module docstring)."""
    benchmark, folders = _sequence_folders(src)
    distractors = MOT20_DISTRACTOR_CLASSES if benchmark.upper().startswith("MOT20") else DISTRACTOR_CLASSES
    cameras: dict[str, tuple[int, int]] = {}
    columns: dict[str, list] = {key: [] for key in ("frame", "actor", "camera", "label", "box", "mark", "reason")}
    lengths, rates, named = [], [], True
    for number_, folder in enumerate(folders):
        info = _seqinfo(folder)
        sequence = _read_sequence(folder, distractors)
        rows = sequence["rows"]
        last = max((r[0] for r in rows), default=-1) + 1
        length = int(info.get("seqLength", last))
        if last > length:
            raise SourceError(f"{sequence['file']}: frame {last} is beyond the sequence's seqLength {length}")
        lengths.append(length)
        rates.append(info.get("frameRate", DEFAULT_FRAME_RATE_HZ))
        camera, label = _camera_and_label(folder.name)
        named &= label is not None
        extent = np.array([[r[4], r[5]] for r in rows]).reshape(-1, 2).max(axis=0, initial=1.0)
        size = (int(info.get("imWidth", np.ceil(extent[0]))), int(info.get("imHeight", np.ceil(extent[1]))))
        if cameras.setdefault(camera, size) != size:
            raise SourceError(f"{folder}: camera {camera!r} has image size {size}, elsewhere {cameras[camera]}")
        for frame, ident, x1, y1, x2, y2, mark, reason in rows:
            columns["frame"].append(frame)
            columns["actor"].append(number_ * ID_STRIDE + ident)
            columns["camera"].append(camera)
            columns["label"].append(label or ActorClass.PEDESTRIAN.value)
            columns["box"].append((x1, y1, x2, y2))
            columns["mark"].append(mark)
            columns["reason"].append(reason)
    rig = Rig("imported", tuple(uncalibrated_camera(name, *size) for name, size in cameras.items()))
    frames = max(lengths)
    rate = float(rates[0])
    frame = np.array(columns["frame"], dtype=np.int64)
    order = np.lexsort((np.array(columns["actor"], dtype=np.int64), frame))
    camera_index = np.array([rig.camera_names.index(name) for name in columns["camera"]], dtype=np.int64)[order]
    n, c = len(order), len(rig.cameras)
    boxes2d = np.full((n, c, 4), np.nan)
    boxes2d[np.arange(n), camera_index] = np.array(columns["box"]).reshape(-1, 4)[order]
    in_view = np.zeros((n, c), dtype=bool)
    in_view[np.arange(n), camera_index] = True
    reasons = np.array(columns["reason"], dtype=object)[order]
    marks = np.array(columns["mark"], dtype=np.int8)[order]
    truth = ImportedTruth(
        name=f"{benchmark}-import", frame_rate_hz=rate, rig=rig, timestamps=np.arange(frames) / rate,
        egos=np.zeros((frames, 6)), frame=frame[order], actor_id=np.array(columns["actor"], dtype=np.int64)[order],
        label=np.array(columns["label"], dtype=object)[order], boxes=np.full((n, 9), np.nan), boxes2d=boxes2d,
        in_view=in_view, occlusion=np.full((n, c), np.nan), ignored=in_view * marks[:, None],
        reasons=reasons, evaluation={**IMPORT_EVALUATION, "classes": "each" if named else ANY},
        source={"format": "motchallenge", "path": str(src), "ground_truth_3d": False, "calibrated_rig": False,
                "causes": "unknown", "sequences": {f.name: {"length": n_, "frame_rate_hz": r}
                                                   for f, n_, r in zip(folders, lengths, rates, strict=True)},
                "id_stride": ID_STRIDE, "distractor_rows": int(np.sum(marks == DISTRACTOR)),
                "unevaluated_rows": int(np.sum(marks == UNEVALUATED))},
    )
    check_unique(truth, str(src))
    return truth
