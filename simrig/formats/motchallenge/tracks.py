"""Tracks in MOTChallenge text: one comma-separated file per camera, read into simrig's 2D tracks table.

A line is ``frame, id, left, top, width, height, conf[, …]`` with frames from 1 and pixel boxes (the columns
after ``conf`` — ``x, y, z`` in MOT16/17 results, ``class, visibility`` in simrig's export — are not read).
Every line of a file must have as many columns as its first line, at least 7.

Where the files are:

- one file ``CAMERA.txt`` or ``CAMERA-CLASS.txt`` (the camera is the dataset's camera name; ``CLASS`` a simrig
  class, or ``any``);
- a folder of such files;
- the folder written by ``simrig export --format motchallenge`` (``trackers/mot_challenge/SIMRIG-test/NAME/data``
  inside it), or a ``NAME`` or ``data`` folder of it.

MOTChallenge results carry no class: a file named ``CAMERA-CLASS.txt`` gives its rows that class; any other
file can be scored only class-agnostically (``--evaluation classes=any``). Errors name the file and line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from simrig.dataset.tracks_file import CLASSES, TRACKS2D_FILE, TRACKS2D_SCHEMA, rows_table
from simrig.errors import TracksError
from simrig.formats.text_rows import numbers, parse_lines

MIN_COLUMNS = 7
COLUMN_NAMES = ("frame", "id", "left", "top", "width", "height", "conf")
ANY = "any"


def _result_files(path: Path) -> list[Path]:
    """The per-camera ``.txt`` files at ``path`` (a file, a folder of them, or an export folder)."""
    if path.is_file():
        return [path]
    exported = path / "trackers" / "mot_challenge"
    if exported.is_dir():
        folders = sorted(p for p in exported.glob("*/*/data") if p.is_dir())
        if len(folders) != 1:
            names = ", ".join(str(p.parent.relative_to(exported)) for p in folders) or "none"
            raise TracksError(f"{path}: a MOTChallenge export needs exactly one tracker to score, found: {names}")
        path = folders[0]
    elif (path / "data").is_dir():
        path = path / "data"
    files = sorted(path.glob("*.txt"))
    if not files:
        raise TracksError(f"{path}: holds no MOTChallenge .txt file")
    return files


def _camera_and_class(file: Path, cameras: tuple[str, ...]) -> tuple[str, str]:
    """(camera, class or ``any``) of a file named ``CAMERA.txt`` or ``CAMERA-CLASS.txt``."""
    stem = file.stem
    if stem in cameras:
        return stem, ANY
    camera, _, label = stem.rpartition("-")
    if camera in cameras and (label in CLASSES or label == ANY):
        return camera, label
    raise TracksError(f"{file}: the file name must be CAMERA.txt or CAMERA-CLASS.txt with a camera of the dataset "
                      f"({', '.join(cameras)}) and a class ({', '.join(CLASSES)}, or {ANY})")


def read_motchallenge(path: Path, *, frame_count: int, cameras: tuple[str, ...], classes: str) -> dict[str, pa.Table]:
    """The 2D tracks table of the MOTChallenge files at ``path`` (``classes``: the evaluation's ``classes``
    setting; rows of a file without a class in its name need ``any``)."""
    rows = []
    for file in _result_files(path):
        camera, label = _camera_and_class(file, cameras)
        if label == ANY:
            if classes != ANY:
                raise TracksError(f"{file}: MOTChallenge rows carry no class; name the file {camera}-CLASS.txt or "
                                  "score class-agnostically (--evaluation classes=any)")
            label = CLASSES[0]  # any label: a class-agnostic score does not read it
        lines = parse_lines(file, ",", MIN_COLUMNS, COLUMN_NAMES)
        values = numbers(file, lines, tuple(range(7)), COLUMN_NAMES, integers=(0, 1))
        frame, track, left, top, width, height, conf = values.T
        frame = frame.astype(np.int64) - 1
        outside = np.flatnonzero((frame < 0) | (frame >= frame_count))
        if len(outside):
            line = lines[outside[0]][0]
            raise TracksError(f"{file}:{line}: frame {frame[outside[0]] + 1} is not in the dataset (frames "
                              f"1…{frame_count} in MOTChallenge's 1-based numbering)")
        empty = np.flatnonzero((width <= 0) | (height <= 0))
        if len(empty):
            line, fields = lines[empty[0]]
            raise TracksError(f"{file}:{line}: box width {fields[4]} and height {fields[5]} must be positive")
        rows += zip(frame.tolist(), [camera] * len(lines), track.astype(np.int64).tolist(), [label] * len(lines),
                    conf.tolist(), left.tolist(), top.tolist(), (left + width).tolist(), (top + height).tolist(),
                    strict=True)
    return {TRACKS2D_FILE: rows_table(rows, TRACKS2D_SCHEMA)}

