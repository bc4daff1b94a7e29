"""How a drive went (closed loop, ``simrig drive``): collisions, time to collision, hard braking and progress, from
the ground truth of the driven world.

* ``collisions``: the ego's collisions — its footprint touching another road user's at the end of a simulation step
  (the dataset's ``collisions`` table, :mod:`simrig.world.collisions`). The ego and what it hit then stand where
  they met, so the progress ends there, and a later collision is something else running into them.
  ``collision_frame``, ``collision_actor`` (−2: a fixed obstacle) and ``collision_speed_mps`` (how fast the two
  closed) describe the first. A dataset made before collisions were recorded gives highway-env's ``ego_crashed``
  events (its flag, no other party, no speed).
* ``min_ttc_s`` [s]: the least time to collision with any vehicle ahead in the ego's path — a vehicle whose
  footprint overlaps the ego's sideways (centres closer across the ego's heading than the two half widths) and
  whose rear is ahead of the ego's front: bumper gap / closing speed along the ego's heading, where closing. Frames
  after a collision do not count (the ego stands still). ``inf`` when nothing ever closed in.
* ``near_misses``: the frames where a time to collision first drops below :data:`NEAR_MISS_TTC_S` (one per run of
  consecutive frames below it), collisions excepted.
* ``hard_brakes``: the frames where the ego's realised deceleration first exceeds :data:`HARD_BRAKE_MPS2` (one per
  run of consecutive frames), from its speed change between frames; the step into a collision (where the ego stops
  dead) is not braking and does not count.
* ``progress_m`` [m]: the path length the ego drove.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from simrig.classes import CLASS_SPECS
from simrig.dataset.ground_truth import GroundTruth
from simrig.types import EGO_ID, ActorClass

NEAR_MISS_TTC_S = 1.5
"""[s] a time to collision below this is a near miss (a common threshold for a critical conflict in traffic-
conflict studies, which use 1–1.5 s)."""
HARD_BRAKE_MPS2 = 4.0
"""[m/s²] a deceleration beyond this is hard braking (≈ 0.4 g; IDM's comfortable braking is 5 m/s², its limit
6 m/s²)."""
EGO_SPEC = CLASS_SPECS[ActorClass.CAR]
DRIVE_COLUMNS = ("drive_collision", "drive_near_misses", "drive_min_ttc_s", "drive_hard_brakes", "drive_progress_m",
                 "drive_progress_lost_m")
"""The closed-loop outcome columns of a bench with ``closed_loop = true``: a collision (1/0), near misses,
the least time to collision [s] (inf: nothing ever closed in), hard brakes, the progress [m], and the progress the
ground-truth drive of the same scenario and seed made beyond it [m]."""



@dataclass(frozen=True)
class DriveOutcome:
    """What happened on one drive (module docstring); frames are frame numbers."""

    frames: int
    collisions: int
    collision_frame: int | None
    collision_actor: int | None
    collision_speed_mps: float | None
    min_ttc_s: float
    min_ttc_frame: int | None
    near_misses: tuple[int, ...]
    hard_brakes: tuple[int, ...]
    progress_m: float

    def to_dict(self) -> dict:
        return {**asdict(self), "min_ttc_s": None if np.isinf(self.min_ttc_s) else self.min_ttc_s,
                "near_misses": list(self.near_misses), "hard_brakes": list(self.hard_brakes)}


def traffic_crashes(truth: GroundTruth) -> int:
    """How many collisions between road users other than the ego (two vehicles, or a vehicle and a fixed obstacle)
    the world of ``truth`` had: the traffic's own crashes, not the ego's."""
    return sum(1 for _, c in truth.collisions if c.geometry and EGO_ID not in (c.first, c.second))


def drive_outcome(truth: GroundTruth) -> DriveOutcome:
    """The outcome of the drive whose ground truth is ``truth`` (module docstring)."""
    crashes = [(frame, c) for frame, c in truth.collisions if EGO_ID in (c.first, c.second)]
    collision, actor, closing_speed = None, None, None
    if crashes:
        collision, first = crashes[0]
        actor = None if first.first == first.second else first.first + first.second - EGO_ID
        closing_speed = float(first.closing_speed) if np.isfinite(first.closing_speed) else None
    ego = np.array([(e.x, e.y, e.yaw, e.vx, e.vy) for e in truth.egos]).reshape(-1, 5)
    ttc = np.full(len(truth.frames), np.inf)
    heading = np.stack([np.cos(ego[:, 2]), np.sin(ego[:, 2])], axis=1)
    position = np.searchsorted(truth.frames, truth.frame)
    offset = truth.boxes[:, :2] - ego[position, :2]
    along = (offset * heading[position]).sum(axis=1)
    across = np.abs(offset[:, 0] * heading[position, 1] - offset[:, 1] * heading[position, 0])
    closing = ((ego[position, 3:5] - truth.boxes[:, 7:9]) * heading[position]).sum(axis=1)
    gap = along - (EGO_SPEC.length + truth.boxes[:, 3]) / 2.0
    ahead = (across < (EGO_SPEC.width + truth.boxes[:, 4]) / 2.0) & (gap > 0.0) & (closing > 0.0)
    np.minimum.at(ttc, position[ahead], gap[ahead] / closing[ahead])
    scored = truth.frames < collision if collision is not None else np.ones(len(truth.frames), bool)
    ttc_scored = np.where(scored, ttc, np.inf)
    speed = (ego[:, 3:5] * heading).sum(axis=1)
    rate = 1.0 / np.diff(truth.timestamps) if len(truth.frames) > 1 else np.zeros(0)
    deceleration = -np.diff(speed) * rate
    hard = np.zeros(len(truth.frames), bool)
    hard[:-1] = deceleration > HARD_BRAKE_MPS2
    step = np.hypot(*np.diff(ego[:, :2], axis=0).T) if len(ego) > 1 else np.zeros(0)
    best = int(np.argmin(ttc_scored)) if len(ttc_scored) else 0
    return DriveOutcome(
        frames=len(truth.frames), collisions=len(crashes), collision_frame=collision,
        collision_actor=actor, collision_speed_mps=closing_speed,
        min_ttc_s=float(ttc_scored[best]) if len(ttc_scored) else float("inf"),
        min_ttc_frame=int(truth.frames[best]) if len(ttc_scored) and np.isfinite(ttc_scored[best]) else None,
        near_misses=_onsets(truth.frames, ttc_scored < NEAR_MISS_TTC_S),
        hard_brakes=_onsets(truth.frames, hard & np.append(scored[1:], False)), progress_m=float(step.sum()),
    )


def _onsets(frames: np.ndarray, flag: np.ndarray) -> tuple[int, ...]:
    """The frame numbers where ``flag`` turns true (the first of each run of consecutive true frames)."""
    starts = flag & ~np.concatenate([[False], flag[:-1]])
    return tuple(int(f) for f in frames[starts])
