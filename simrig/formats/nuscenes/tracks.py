"""Tracks in the nuScenes tracking-results JSON, read into simrig's 3D tracks table.

``{"meta": {...}, "results": {sample_token: [box, …]}}``; per box ``translation`` (world-frame centre [m]),
``size`` (width, length, height [m]), ``rotation`` (unit quaternion w, x, y, z; its yaw about +z is kept),
``velocity`` (vx, vy [m/s]), ``tracking_id`` (a string), ``tracking_name``, ``tracking_score``. A
detection-results JSON (read by :func:`read_results` for ``simrig detector fit``) has ``detection_name`` and
``detection_score`` instead and no id. A dataset's sample tokens are ``SCENARIO-seedN-FFFFFF``
(:func:`~simrig.formats.nuscenes.samples.sample_token`, as ``simrig export --format nuscenes`` writes them).
Track ids that are all integers are kept; otherwise each distinct id gets a number in sorted order; on a
dataset of several scenes (a nuScenes import) an id names one track per scene, as in the devkit, and every
(scene, id) gets its own number. Boxes whose ``tracking_name`` is not a simrig class (``trailer`` …) are left
out. Errors name the file and the line of the sample token in it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow as pa

from simrig.dataset.tracks_file import CLASSES, TRACKS3D_FILE, TRACKS3D_SCHEMA, rows_table
from simrig.errors import SimrigError, TracksError
from simrig.reading import read_capped

MAX_RESULTS_BYTES = 2 * 2**30
"""[bytes] the largest results JSON read (nuScenes' full validation results are about 1 GB)."""
BOX_KEYS = ("translation", "size", "rotation", "velocity", "tracking_id", "tracking_name", "tracking_score")


def _line_of(text: str, needle: str) -> int:
    at = text.find(needle)
    return text.count("\n", 0, at) + 1 if at >= 0 else 1


class _Where:
    """``FILE:LINE`` of a sample token, found only when an error is written (a detection-results JSON may
    hold thousands of samples in hundreds of megabytes)."""

    def __init__(self, path: Path, text: str, token: str):
        self.path, self.text, self.token = path, text, token

    def __str__(self) -> str:
        needle = '"' + self.token + '"'
        return f"{self.path}:{_line_of(self.text, needle)}"


def read_results(path: Path, *, tokens: dict[str, int], kind: str = "tracking",
                 error: type[SimrigError] = TracksError) -> tuple[list[tuple], list[int]]:
    """The boxes of the nuScenes ``kind`` (``tracking`` or ``detection``) results JSON at ``path``: rows
    ``(frame, id, name, score, x, y, z, length, width, height, yaw, vx, vy)`` (``id`` the ``tracking_id``; ""
    for detections) of the boxes whose ``{kind}_name`` is a simrig class, and the frames the file has a key
    for (empty lists count). ``tokens``: the dataset's sample token → frame. Errors (``error``) name the file
    and the line of the sample token."""
    try:
        text = read_capped(path, f"nuScenes {kind} results", error, max_bytes=MAX_RESULTS_BYTES).decode("utf-8")
        document = json.loads(text)
    except (OSError, UnicodeDecodeError) as problem:
        raise error(f"{path}: cannot be read as text ({problem})") from None
    except json.JSONDecodeError as problem:
        raise error(f"{path}:{problem.lineno}: not JSON ({problem.msg})") from None
    results = document.get("results") if isinstance(document, dict) else None
    if not isinstance(results, dict):
        raise error(f"{path}:1: no \"results\" mapping of sample tokens to boxes (nuScenes {kind} results)")
    known = sorted(tokens, key=tokens.get)
    keys = (*BOX_KEYS[:4], *(("tracking_id",) if kind == "tracking" else ()), f"{kind}_name", f"{kind}_score")
    boxes, frames = [], []
    for token, items in results.items():
        where = _Where(path, text, token)
        if token not in tokens:
            raise error(f"{where}: unknown sample token {token!r} (this dataset's are {known[0]} … "
                        f"{known[-1]})")
        if not isinstance(items, list):
            raise error(f"{where}: sample {token!r} must map to a list of boxes")
        frames.append(tokens[token])
        for k, box in enumerate(items):
            missing = [key for key in keys if not isinstance(box, dict) or key not in box]
            if missing:
                raise error(f"{where}: sample {token!r}, box {k}: missing {', '.join(missing)}")
            if box[f"{kind}_name"] not in CLASSES:
                continue
            try:
                x, y, z = (float(v) for v in box["translation"])
                width, length, height = (float(v) for v in box["size"])
                w, qx, qy, qz = (float(v) for v in box["rotation"])
                vx, vy = (float(v) for v in box["velocity"])
                score = float(box[f"{kind}_score"])
            except (TypeError, ValueError) as problem:
                raise error(f"{where}: sample {token!r}, box {k}: {problem} (translation 3, size 3, "
                            f"rotation 4, velocity 2 numbers, {kind}_score a number)") from None
            norm = math.sqrt(w * w + qx * qx + qy * qy + qz * qz)
            if not 0.5 < norm < 1.5:  # a unit quaternion, give or take the digits a file was printed with
                raise error(f"{where}: sample {token!r}, box {k}: rotation {box['rotation']} is not a unit "
                            f"quaternion (norm {norm:g})")
            if not 0.0 <= score <= 1.0:
                raise error(f"{where}: sample {token!r}, box {k}: {kind}_score {score} is outside 0 … 1")
            yaw = float(np.arctan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz)))
            boxes.append((tokens[token], str(box.get("tracking_id", "")), box[f"{kind}_name"], score,
                          x, y, z, length, width, height, yaw, vx, vy))
    return boxes, frames


def read_nuscenes(path: Path, *, tokens: dict[str, int], scenes: np.ndarray | None = None) -> dict[str, pa.Table]:
    """The 3D tracks table of the results JSON at ``path``; ``tokens``: the dataset's sample token → frame;
    ``scenes``: ``(F,)`` scene index of every frame, or ``None`` for one scene."""
    boxes, _ = read_results(path, tokens=tokens)
    if scenes is not None:
        keys = [(int(scenes[b[0]]), b[1]) for b in boxes]
        number = {key: k for k, key in enumerate(sorted(set(keys)))}
        rows = [(b[0], number[key], *b[2:]) for b, key in zip(boxes, keys, strict=True)]
        return {TRACKS3D_FILE: rows_table(rows, TRACKS3D_SCHEMA)}
    names = sorted({b[1] for b in boxes})
    try:
        number = {name: int(name) for name in names}
    except ValueError:
        number = {name: k for k, name in enumerate(names)}
    rows = [(b[0], number[b[1]], *b[2:]) for b in boxes]
    return {TRACKS3D_FILE: rows_table(rows, TRACKS3D_SCHEMA)}
