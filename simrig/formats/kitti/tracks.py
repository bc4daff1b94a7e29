"""Tracks in KITTI tracking label format, read into simrig's 2D tracks table.

A line is ``frame track_id type truncated occluded alpha left top right bottom height width length x y z
rotation_y [score]`` (space-separated, frames from 0, pixel boxes); every line of a file has as many fields as
its first, 17 or 18 (without a score, every row scores 1). Only the pixel box is read: the 3D fields are in a
KITTI camera frame simrig's scorer does not take tracks in. Types map to simrig classes as ``simrig export``
writes them — ``Car`` and ``Van`` → car, ``Truck`` → truck, ``Misc`` → bus, ``Cyclist`` → motorcycle,
``Pedestrian`` → pedestrian; rows of other types (``Person_sitting``, ``Tram``, ``DontCare``) and rows with id −1
are not tracks of a simrig class and are left out.

Where the files are: one file ``CAMERA.txt``; a folder of them; or the folder written by ``simrig export
--format kitti`` (``CAMERA/NAME/0000.txt``, next to the ground truth's ``CAMERA/label_02/``). Errors name the
file and line.
"""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa

from simrig.dataset.tracks_file import TRACKS2D_FILE, TRACKS2D_SCHEMA, rows_table
from simrig.errors import TracksError
from simrig.formats.text_rows import integer, number, parse_lines

FIELDS = ("frame", "track_id", "type", "truncated", "occluded", "alpha", "left", "top", "right", "bottom",
          "height", "width", "length", "x", "y", "z", "rotation_y", "score")
CLASS_OF_TYPE = {"Car": "car", "Van": "car", "Truck": "truck", "Misc": "bus", "Cyclist": "motorcycle",
                 "Pedestrian": "pedestrian"}
GROUND_TRUTH_FOLDER = "label_02"


def label_files(path: Path, cameras: tuple[str, ...]) -> dict[str, Path]:
    """camera → the tracker's label file at ``path`` (a ``CAMERA.txt``, a folder of them, or an export)."""
    if path.is_file():
        files = [path]
    else:
        exported = {c: sorted(p for p in (path / c).iterdir() if p.is_dir() and p.name != GROUND_TRUTH_FOLDER)
                    for c in cameras if (path / c).is_dir()}
        if exported:
            names = sorted({p.name for found in exported.values() for p in found})
            if len(names) != 1:
                raise TracksError(f"{path}: a KITTI export needs exactly one tracker to score, found: "
                                  f"{', '.join(names) or 'none'}")
            return {c: found[0] / "0000.txt" for c, found in exported.items() if (found[0] / "0000.txt").exists()}
        files = sorted(path.glob("*.txt"))
        if not files:
            raise TracksError(f"{path}: holds no KITTI .txt file")
    for file in files:
        if file.stem not in cameras:
            raise TracksError(f"{file}: the file name must be CAMERA.txt with a camera of the dataset "
                              f"({', '.join(cameras)})")
    return {file.stem: file for file in files}


def read_kitti(path: Path, *, frame_count: int, cameras: tuple[str, ...]) -> dict[str, pa.Table]:
    """The 2D tracks table of the KITTI label files at ``path``."""
    rows = []
    for camera, file in label_files(path, cameras).items():
        for line, fields in parse_lines(file, None, 17, FIELDS):
            if len(fields) > 18:
                raise TracksError(f"{file}:{line}: {len(fields)} fields where 17 or 18 are expected")
            numeric = [k for k in range(len(fields)) if k != 2]
            values = {k: number(file, line, fields, k, FIELDS) for k in numeric}
            frame, track = integer(file, line, fields, 0, FIELDS), integer(file, line, fields, 1, FIELDS)
            label = CLASS_OF_TYPE.get(fields[2])
            if label is None or track < 0:
                continue
            if not 0 <= frame < frame_count:
                raise TracksError(f"{file}:{line}: frame {frame} is not in the dataset (frames 0…{frame_count - 1})")
            left, top, right, bottom = (values[k] for k in range(6, 10))
            if right <= left or bottom <= top:
                raise TracksError(f"{file}:{line}: empty box {[left, top, right, bottom]} (needs right > left and "
                                  "bottom > top)")
            score = values.get(17, 1.0)
            rows.append((frame, camera, track, label, score, left, top, right, bottom))
    return {TRACKS2D_FILE: rows_table(rows, TRACKS2D_SCHEMA)}
