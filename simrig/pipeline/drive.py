"""``simrig drive``: the tracker in the loop. The ego is driven by its own planner (IDM + MOBIL) fed, frame by frame,
with what the tracker reports, inside the simulation; everything else — the other vehicles, the detector's draws,
the seed — is the scenario's. Each drive is a normal dataset (its ground truth is the world as driven) with the
tracker's tracks beside it, so it can also be scored open loop.

Per frame t: the world at t → the sensor model → the frame is written → the tracker's ``step`` on exactly what
:meth:`~simrig.dataset.Dataset.sensor_frames` would give it → its 3D tracks within their class's evaluation range
(:data:`~simrig.scoring.inputs.CLASS_RANGE_M`, as the open-loop scores keep them) become the vehicles the ego's
planner decides on for the step t → t + 1 (:func:`~simrig.world.ego_planner.drive_on_perception`). The reference
drive, ``perception = "ground truth"``, gives the planner the ground truth within the same ranges: a perfect
perception of that range. At a dropped sensor frame the tracker is not stepped and the planner keeps its last
tracks, moved on at their velocities. Other vehicles still see the real ego and react to it, and new vehicles are
spawned around wherever the ego is, so two drives are compared by outcome
(:mod:`simrig.scoring.drive_outcome`), not frame by frame.

Not offered (a clear error before any work): scenarios with capture timing, latency or an ego-pose error (the
tracker's frames would need the delivery schedule) and a 2D-only tracker (the planner needs 3D tracks).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.dataset import Dataset
from simrig.dataset.delivery import frame_detections
from simrig.dataset.manifest import write_json_atomic
from simrig.dataset.outputs import check_own_folder, write_text_atomic
from simrig.dataset.run_folder import DATASET_DIR, REPORT, TRACKS_DIR, what_folder_holds
from simrig.dataset.tracks_file import TrackTables, write_tracks
from simrig.dataset.writer import arrow_table
from simrig.errors import DatasetError, SimrigError
from simrig.pipeline.content_keys import drive_key
from simrig.pipeline.generate import generate
from simrig.pipeline.guard import FRAME_TIME_LIMIT_S, checked_tracks
from simrig.pipeline.run import command_line, run_label
from simrig.pipeline.track import build_tracker, guarded_call, tracker_display, tracker_reference
from simrig.reading import read_json
from simrig.rig import build_rig
from simrig.scenarios import Scenario
from simrig.scenarios.timing_schema import timing_tables_set
from simrig.scoring.drive_outcome import HARD_BRAKE_MPS2, NEAR_MISS_TTC_S, DriveOutcome, drive_outcome, traffic_crashes
from simrig.scoring.inputs import class_ranges
from simrig.types import OBSTACLE_ID, GroundTruthFrame, SensorFrame, Track

GROUND_TRUTH = "ground truth"
"""The perception of the reference drive."""


class DriveError(SimrigError):
    """A drive cannot run: the message names the scenario setting, the tracker or the frame."""


@dataclass(frozen=True)
class DriveResult:
    """One drive: its dataset folder, its tracks folder (None for the ground-truth drive), its outcome, and the
    seconds spent in the tracker's ``step`` and in the whole drive."""

    perception: str
    dataset: Path
    tracks: Path | None
    outcome: DriveOutcome
    step_seconds: float
    seconds: float


def drive(scenario: Scenario, *, seed: int, out: Path | str, tracker=None, params: dict | None = None,
          frames: int | None = None, overwrite: bool = False, progress: bool = False,
          frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S) -> DriveResult:
    """Drive ``scenario`` with ``seed`` closed loop on ``tracker`` (anything
    :func:`~simrig.pipeline.track.build_tracker` takes, with ``params``; None: the ground-truth drive) into
    ``out`` (``out/dataset``, and ``out/tracks`` for a tracker). Same scenario, seed, tracker and parameters: the
    same bytes."""
    check_drivable(scenario)
    out = Path(out)
    started = time.perf_counter()
    rig = build_rig(scenario.rig)
    if tracker is None:
        perception = _TruthPerception()
    else:
        built = build_tracker(tracker, params)
        perception = _TrackerPerception(built, tracker_display(tracker), tracker_reference(tracker), params, rig,
                                        seed, scenario, frame_time_limit_s)
    generate(scenario, seed=seed, out=out / DATASET_DIR, frames=frames, overwrite=overwrite, progress=progress,
             driver=perception)
    dataset = Dataset.open(out / DATASET_DIR)
    tracks = None
    if isinstance(perception, _TrackerPerception):
        tracks = write_tracks(out / TRACKS_DIR, perception.tables.tables(), made_on=dataset.identity)
    return DriveResult(perception.record["perception"], dataset.path, tracks, drive_outcome(dataset.ground_truth),
                       getattr(perception, "step_seconds", 0.0), time.perf_counter() - started)


def check_drivable(scenario: Scenario) -> None:
    """A :class:`DriveError` naming the setting when ``scenario`` cannot be driven closed loop (module docstring)."""
    timing = timing_tables_set(scenario.sensor)
    if timing:
        raise DriveError(f"{scenario.name}: [sensor.{sorted(timing)[0]}] is set; a closed-loop drive needs every "
                         "camera's detections at its frame (remove the capture timing, latency and ego-pose tables)")


def tracks_in_range(labels: np.ndarray, boxes: np.ndarray, ego) -> np.ndarray:
    """Which world boxes ``(N, 9)`` of class names ``labels`` lie within their class's evaluation range of the ego
    pose ``ego`` (the same test as :func:`~simrig.scoring.inputs.in_class_range`)."""
    return np.hypot(boxes[:, 0] - ego.x, boxes[:, 1] - ego.y) < class_ranges(labels)


class _TruthPerception:
    """The reference drive's perception: the ground truth within the class ranges."""

    record = {"perception": GROUND_TRUTH}

    def decide(self, state: GroundTruthFrame, columns: dict) -> tuple[np.ndarray, np.ndarray]:
        keep = tracks_in_range(state.classes.astype(str), state.boxes, state.ego)
        return state.boxes[keep], state.actor_ids[keep]


class _TrackerPerception:
    """A tracker stepped inside the simulation: what it is given is what the dataset reader would give it."""

    def __init__(self, tracker, label: str, reference: str | None, params: dict | None, rig, seed: int,
                 scenario: Scenario, frame_time_limit_s: float | None):
        self.tracker, self.label, self.rig = tracker, label, rig
        self.record = {"perception": label, "tracker": reference, "params": params or {}}
        self.limit = frame_time_limit_s
        self.tables = TrackTables()
        self.step_seconds = 0.0
        self._last: tuple[float, np.ndarray, np.ndarray] | None = None
        with guarded_call(label, "reset()", frame_time_limit_s):
            tracker.reset(rig=rig, seed=seed)

    def decide(self, state: GroundTruthFrame, columns: dict) -> tuple[np.ndarray, np.ndarray]:
        if bool(columns["frames"]["dropped"][0]):  # not stepped: the last tracks, moved on at their velocities
            if self._last is None:
                return np.zeros((0, 9)), np.zeros(0, np.int64)
            timestamp, boxes, idents = self._last
            moved = boxes.copy()
            moved[:, :2] += boxes[:, 7:9] * (state.timestamp - timestamp)
            return moved, idents
        detections = columns["detections"]
        dimension = len(detections["embedding"]) and len(detections["embedding"][0])
        arrays = frame_detections(arrow_table("detections", [detections]), state.frame, self.rig, dimension)
        frame = SensorFrame(state.frame, state.timestamp, state.ego, self.rig, arrays=arrays)
        start = time.perf_counter()
        with guarded_call(self.label, f"frame {state.frame}: step()", self.limit):
            returned = self.tracker.step(frame)
        self.step_seconds += time.perf_counter() - start
        tracks = checked_tracks(returned, tracker=self.label, frame=state.frame, cameras=self.rig.camera_names)
        self.tables.add(state.frame, tracks)
        boxes, idents, labels = _boxes_of(tracks, self.label, state.frame)
        keep = tracks_in_range(labels, boxes, state.ego)
        self._last = (state.timestamp, boxes[keep], idents[keep])
        return boxes[keep], idents[keep]


def _boxes_of(tracks: list[Track], tracker: str, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World boxes ``(N, 9)``, track ids and class names of ``tracks``; a :class:`DriveError` for a track without
    a 3D box (a 2D tracker)."""
    flat = [t for t in tracks if t.box3d is None]
    if flat:
        raise DriveError(f"tracker {tracker!r}: frame {frame}: track {flat[0].track_id} has no 3D box; the ego's "
                         "planner drives on 3D tracks (position, velocity, size), so a 2D tracker cannot drive")
    boxes = np.array([t.box3d.as_array() for t in tracks], dtype=float).reshape(-1, 9)
    idents = np.array([t.track_id for t in tracks], dtype=np.int64)
    labels = np.array([str(getattr(t.label, "value", t.label)) for t in tracks], dtype=object)
    return boxes, idents, labels


REFERENCE_DIR = "reference"
"""The ground-truth drive's folder in a drive folder."""
DRIVES_DIR = "drives"
"""The tracker drives' folders (``drives/LABEL``) in a drive folder."""
OUTCOME_FILE = "outcome.json"


@dataclass(frozen=True)
class DriveComparison:
    """``simrig drive``'s result: the reference drive and the tracker's, the folder's report and the files
    written."""

    reference: DriveResult
    tracked: DriveResult
    report: Path
    reused: bool


def drive_folder(scenario: Scenario, *, seed: int, tracker, out: Path | str, params: dict | None = None,
                 frames: int | None = None, progress: bool = False,
                 frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S) -> DriveComparison:
    """The ground-truth drive (``out/reference``, made once: a folder holds the drives of one scenario, seed and
    frame count) and the drive on ``tracker`` (``out/drives/LABEL``, made again each time), each with
    ``outcome.json``; ``out/report.md`` compares every drive in the folder."""
    check_drivable(scenario)
    out = Path(out)
    check_own_folder(out, what="drive folder", marker=REPORT, made=(REFERENCE_DIR, DRIVES_DIR),
                     hint=what_folder_holds(out) if out.is_dir() else "")
    reference_dir = out / REFERENCE_DIR
    key = drive_key(scenario, seed, frames, _TruthPerception.record)
    held = _drive_manifest(reference_dir / DATASET_DIR)
    if held is not None and held.get("world_key") != key:
        raise DriveError(f"{out}: holds the drives of {held['scenario']['name']!r}, seed {held['seed']}, "
                         f"{held['frames']} frames; drives compared in one folder share the scenario, seed and "
                         "frames: choose another --out")
    reused = held is not None
    reference_name = tracker_reference(tracker)
    label = run_label(reference_name or tracker_display(tracker), params, None)
    folder = out / DRIVES_DIR / label
    try:  # the tracker first: a tracker that cannot drive says so before the reference is made
        tracked = drive(scenario, seed=seed, out=folder, tracker=tracker, params=params, frames=frames,
                        overwrite=True, progress=progress, frame_time_limit_s=frame_time_limit_s)
    except BaseException:
        for left in (folder, folder.parent, out):  # nothing of a drive that could not run stays behind
            if left.is_dir() and not any(left.iterdir()):
                left.rmdir()
        raise
    reference = (_read_drive(reference_dir, GROUND_TRUTH) if reused
                 else drive(scenario, seed=seed, out=reference_dir, frames=frames, overwrite=True, progress=progress))
    for result, folder in ((reference, reference_dir), (tracked, out / DRIVES_DIR / label)):
        write_json_atomic(folder / OUTCOME_FILE, {
            "perception": result.perception, "scenario": scenario.name, "seed": seed,
            "command": command_line(scenario, seed, reference_name or tracker_display(tracker), params, frames,
                                    verb="drive"), **result.outcome.to_dict()})
    report = out / REPORT
    write_text_atomic(report, drive_report(out))
    return DriveComparison(reference, tracked, report, reused)


def _drive_manifest(dataset: Path) -> dict | None:
    """The manifest of the complete drive dataset ``dataset``; None when there is none."""
    try:
        manifest = Dataset.open(dataset).manifest
    except DatasetError:
        return None
    return manifest if "drive" in manifest else None


def _read_drive(folder: Path, perception: str) -> DriveResult:
    dataset = Dataset.open(folder / DATASET_DIR)
    return DriveResult(perception, dataset.path, None, drive_outcome(dataset.ground_truth), 0.0, 0.0)


def drive_report(out: Path) -> str:
    """``out/report.md``: the outcome of every drive in the folder, the reference first (module docstring of
    :mod:`simrig.scoring.drive_outcome` for the definitions)."""
    folders = [out / REFERENCE_DIR, *sorted(p for p in (out / DRIVES_DIR).glob("*") if p.is_dir())]
    rows = []
    for folder in folders:
        path = folder / OUTCOME_FILE
        if path.is_file():
            rows.append(read_json(path, OUTCOME_FILE, DriveError))
    if not rows:
        return "# Drives\n\nNo drive has finished in this folder yet.\n"
    first = rows[0]
    lines = [f"# Closed-loop drives: {first['scenario']}, seed {first['seed']}", "",
             "The ego driven by its own planner (IDM + MOBIL) on each perception; `ground truth` is the reference "
             f"(the ground truth within the class ranges). Near miss: time to collision below {NEAR_MISS_TTC_S} s; "
             f"hard brake: deceleration above {HARD_BRAKE_MPS2} m/s² (frames where each starts).", "",
             "Collision: the ego's footprint touched another road user's (frame, who, closing speed); the ego and "
             "what it hit then stand where they met, so progress ends there.", "",
             "| perception | collision (frame, actor, closing speed) | min TTC [s] (frame) | near misses (frames) "
             "| hard brakes (frames) | progress [m] |", "|---|---|---|---|---|---|"]
    for row in rows:
        ttc = "–" if row["min_ttc_s"] is None else f"{row['min_ttc_s']:.2f} ({row['min_ttc_frame']})"
        lines.append(f"| {row['perception']} | {collision_text(row)} | {ttc} | {_frames(row['near_misses'])} "
                     f"| {_frames(row['hard_brakes'])} | {row['progress_m']:.1f} |")
    if rows[0]["perception"] == GROUND_TRUTH and rows[0]["collisions"]:
        lines += ["", f"**The ground-truth drive itself collides** (frame {rows[0]['collision_frame']}): in this "
                  "scenario and seed the ego's planner crashes on perfect perception, so a tracker's collision here "
                  "is not the tracker's alone."]
    lines += ["", "Produced by:", ""] + [f"- `{row['command']}`" for row in rows[1:]]
    return "\n".join(lines) + "\n"


def collision_text(row: dict) -> str:
    """A drive outcome's collision as the report writes it: ``no``, or ``yes (frame F, actor A, S m/s)``."""
    if not row["collisions"]:
        return "no"
    actor = row.get("collision_actor")
    who = "" if actor is None else (", an obstacle" if actor == OBSTACLE_ID else f", actor {actor}")
    speed = row.get("collision_speed_mps")
    closing = "" if speed is None else f", {speed:.1f} m/s"
    return f"yes (frame {row['collision_frame']}{who}{closing})"


def _frames(frames: list[int]) -> str:
    return "–" if not frames else f"{len(frames)}: " + ", ".join(str(f) for f in frames[:8]) + (
        ", …" if len(frames) > 8 else "")


@dataclass(frozen=True)
class ClosedLoopScore:
    """A tracker's drive scored: the score report of its tracks on its own drive's dataset (open loop on the world
    it drove; None when not asked for), and the drive outcomes (:data:`~simrig.scoring.drive_outcome.DRIVE_COLUMNS`)."""

    report: object
    outcomes: dict[str, float]
    step_seconds: float


def closed_loop_score(scenario: Scenario, seed: int, tracker, params: dict | None, frames: int | None,
                      reference: DriveOutcome, frame_time_limit_s: float | None = FRAME_TIME_LIMIT_S, *,
                      scored: bool = True) -> ClosedLoopScore:
    """Drive ``scenario`` on ``tracker`` in a temporary folder (removed after: a drive is made again exactly from
    its scenario, seed and tracker), score it unless not ``scored``, and compare its outcome with ``reference``
    (the ground-truth drive's: :func:`reference_drive`)."""
    from simrig.scoring import score

    with tempfile.TemporaryDirectory(prefix="simrig-drive-") as work:
        result = drive(scenario, seed=seed, out=Path(work), tracker=tracker, params=params, frames=frames,
                       frame_time_limit_s=frame_time_limit_s)
        driven = Dataset.open(result.dataset)
        report = score(driven, result.tracks) if scored else None
        crashes = traffic_crashes(driven.ground_truth)
    outcome = result.outcome
    values = {
        "drive_collision": float(outcome.collisions > 0), "drive_near_misses": float(len(outcome.near_misses)),
        "drive_min_ttc_s": outcome.min_ttc_s, "drive_hard_brakes": float(len(outcome.hard_brakes)),
        "drive_progress_m": outcome.progress_m, "drive_progress_lost_m": reference.progress_m - outcome.progress_m,
        "traffic_crashes": float(crashes),
    }
    return ClosedLoopScore(report, values, result.step_seconds)


def reference_drive(scenario: Scenario, seed: int, frames: int | None, out: Path) -> DriveResult:
    """The ground-truth drive of ``scenario`` and ``seed``, made in ``out`` (``out/dataset``)."""
    return drive(scenario, seed=seed, out=out, frames=frames)
