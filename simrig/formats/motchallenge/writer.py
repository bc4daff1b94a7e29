"""MOTChallenge export, laid out as TrackEval's ``MotChallenge2DBox`` reads it.

``OUT/gt/mot_challenge/SIMRIG-test/CAMERA-CLASS/{gt/gt.txt, seqinfo.ini}``, the seqmap
``OUT/gt/mot_challenge/seqmaps/SIMRIG-test.txt`` and, with tracks,
``OUT/trackers/mot_challenge/SIMRIG-test/NAME/data/CAMERA-CLASS.txt``. One sequence per (camera, class): simrig
matches within a class, and TrackEval's combined result over the sequences then equals ``simrig score``'s
overall one (class-agnostic settings, ``classes = "any"``: one sequence per camera, ``CAMERA-any``). Rows:
``frame, id, left, top, width, height, conf, class, visibility`` with frames from 1 (the dataset's frame + 1),
pixel boxes; the class column is 1 (``pedestrian``, the one class TrackEval's MOT reader evaluates; the real
class is in the sequence name) on both sides, and 8 (``distractor``) for ground truth the evaluation region
ignores: TrackEval's preprocessing then removes the tracker boxes matched to it and the box itself, exactly
as ``simrig score`` does; ground truth ignored only as not evaluated (an imported MOTChallenge row of another
class) is written with ``consider`` 0, which TrackEval matches but neither scores nor lets remove a tracker box.
Frames are the scene's frames, in every sequence: ``seqinfo.ini`` gives the scene's ``frameRate``, and a camera
slower than the frame rate (``sensor.capture.rate_hz``) has no image, no ground truth and so nothing to match at the
frames it skips (a tracker's box there is a false positive, as in ``simrig score``); its own rate is the extra key
``cameraRate`` [Hz], which TrackEval ignores. Evaluate with
``trackeval.datasets.MotChallenge2DBox({"GT_FOLDER": OUT/gt/mot_challenge, "TRACKERS_FOLDER":
OUT/trackers/mot_challenge, "BENCHMARK": "SIMRIG", "SPLIT_TO_EVAL": "test"})``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simrig.formats.evaluation import KEEPS_MATCHES
from simrig.formats.export_input import ExportInput

BENCHMARK, SPLIT = "SIMRIG", "test"
EVALUATED_CLASS, DISTRACTOR_CLASS = 1, 8
"""MOTChallenge class ids: ``pedestrian`` (evaluated) and ``distractor`` (TrackEval's ``distractor_classes``)."""


def _lines(frame, ids, boxes, conf, classes, visibility: int) -> str:
    order = np.lexsort((ids, frame))
    return "".join(
        f"{int(f) + 1},{int(i)},{b[0]:.17g},{b[1]:.17g},{b[2] - b[0]:.17g},{b[3] - b[1]:.17g},{c:.6g},{k},"
        f"{visibility}\n"
        for f, i, b, c, k in zip(frame[order], ids[order], boxes[order], conf[order], classes[order], strict=True)
    )


def camera_rate(capture_offsets: np.ndarray | None, camera: int, frame_rate: float) -> float:
    """[Hz] how often camera ``camera`` took an image: the frame rate divided by the frames between its first two
    images (capture offsets ``(F, C)`` [s], NaN where it took none; ``None``: every camera at every frame)."""
    if capture_offsets is None:
        return frame_rate
    shots = np.flatnonzero(np.isfinite(capture_offsets[:, camera]))
    return frame_rate / int(shots[1] - shots[0]) if len(shots) > 1 else frame_rate


def write(data: ExportInput, out: Path) -> None:
    truth, rig = data.truth, data.truth.rig
    gt_root = out / "gt" / "mot_challenge"
    sequences = []
    frame_rate = float(data.dataset.scenario["frame_rate_hz"])
    agnostic = data.evaluation.classes == "any"
    for c, camera in enumerate(rig.camera_names):
        gt_rows = np.nonzero(truth.in_view[:, c])[0]
        labels = set(truth.label[gt_rows].tolist())
        track_rows = np.zeros(0, dtype=np.int64)
        if data.rows2d is not None:
            track_rows = np.nonzero(data.rows2d.camera == camera)[0]
            labels |= set(data.rows2d.label[track_rows].tolist())
        if agnostic:
            labels = {"any"} if labels else set()
        cam = rig.camera(camera)
        for label in sorted(labels):
            name = f"{camera}-{label}"
            sequences.append(name)
            g = gt_rows if agnostic else gt_rows[truth.label[gt_rows] == label]
            rules = data.ignored[g, c]
            keeps_match = (rules != 0) & ((rules & ~KEEPS_MATCHES) == 0)  # unevaluated: consider 0, class 1
            classes = np.where((rules != 0) & ~keeps_match, DISTRACTOR_CLASS, EVALUATED_CLASS)
            folder = gt_root / f"{BENCHMARK}-{SPLIT}" / name
            (folder / "gt").mkdir(parents=True)
            (folder / "gt" / "gt.txt").write_text(
                _lines(truth.frame[g], truth.actor_id[g], truth.boxes2d_in(g, c), (~keeps_match).astype(float), classes,
                       1))
            (folder / "seqinfo.ini").write_text(
                f"[Sequence]\nname={name}\nseqLength={len(truth.frames)}\nframeRate={frame_rate:g}\n"
                f"cameraRate={camera_rate(truth.capture_offsets, c, frame_rate):g}\n"
                f"imWidth={cam.width}\nimHeight={cam.height}\nimExt=.png\n")
            if data.rows2d is not None:
                t = track_rows if agnostic else track_rows[data.rows2d.label[track_rows] == label]
                folder = out / "trackers" / "mot_challenge" / f"{BENCHMARK}-{SPLIT}" / data.tracker_name / "data"
                folder.mkdir(parents=True, exist_ok=True)
                rows = data.rows2d
                (folder / f"{name}.txt").write_text(
                    _lines(rows.frame[t], rows.track_id[t], rows.boxes[t], rows.score[t],
                           np.full(len(t), EVALUATED_CLASS), -1))
    (gt_root / "seqmaps").mkdir(parents=True)
    (gt_root / "seqmaps" / f"{BENCHMARK}-{SPLIT}.txt").write_text("name\n" + "".join(f"{s}\n" for s in sequences))
