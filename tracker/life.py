"""Track life cycles: when a detection starts a track, when a track dies, when it is reported.

Two rules, both counting on :class:`TrackLife` records that the coordinator keeps per track:

* :class:`HitsAndAge` — AB3DMOT/SimpleTrack: a track is reported once it has ``min_hits`` updates and only
  in frames where it was updated; it dies after ``max_age_s`` seconds without an update.
* :class:`QueryLife` — MUTR3D's query life management (Zhang, Chen, Wang, Zhao: "MUTR3D: A Multi-camera
  Tracking Framework via 3D-to-2D Queries", CVPR Workshops 2022): a detection starts a track only if its
  score ≥ τ_new; a frame whose score (the best assigned detection's, 0 when none) is below τ_old counts a
  miss; a track is reported while its score ≥ τ_old. When a track dies depends on ``reset``:

  - ``"paper"`` (life ``mutr3d``, the default): §3.4 — "removed if its score has been below τ_old for T
    successive frames": any frame at or above τ_old resets the count, so T = ``max_misses`` *consecutive*
    frames below τ_old kill it;
  - ``"tau_new"`` (life ``mutr3d_code``): the public code (a1600012888/MUTR3D,
    ``plugin/track/models/tracker.py``) resets the count only at a score ≥ τ_new, so ``max_misses`` frames
    below τ_old kill a track even if frames between τ_old and τ_new separate them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class TrackLife:
    """Counters of one track. hits: updates so far; since_update: seconds since the last update [s];
    misses: consecutive missed frames (MUTR3D rule); score: the frame's score, in [0, 1]."""

    hits: int = 1
    since_update: float = 0.0
    misses: int = 0
    score: float = 0.0


@dataclass(frozen=True)
class HitsAndAge:
    """min_hits: updates before a track is reported [-]; max_age_s: seconds without update before it dies
    [s]; min_score: lowest detection score that may start a track [-]."""

    min_hits: int = 1
    max_age_s: float = 1.0
    min_score: float = 0.0

    def __post_init__(self) -> None:
        if self.min_hits < 0 or self.max_age_s < 0 or not 0 <= self.min_score <= 1:
            raise ValueError(f"HitsAndAge: need min_hits ≥ 0, max_age_s ≥ 0, min_score in [0, 1]; got {self}")

    def may_start(self, score: float) -> bool:
        return score >= self.min_score

    def observe(self, life: TrackLife, score: float | None, dt: float) -> None:
        """Record a frame: ``score`` of the assigned detections, or None when none was assigned."""
        if score is None:
            life.since_update += dt
        else:
            life.hits += 1
            life.since_update = 0.0
            life.score = score

    def is_dead(self, life: TrackLife) -> bool:
        return life.since_update > self.max_age_s

    def is_reported(self, life: TrackLife) -> bool:
        return life.since_update == 0.0 and life.hits >= self.min_hits


QUERY_RESETS = ("paper", "tau_new")
"""What resets a track's miss count: any score ≥ τ_old (§3.4) or only a score ≥ τ_new (the public code)."""


@dataclass(frozen=True)
class QueryLife:
    """MUTR3D's query life management: tau_new τ_new, tau_old τ_old [-], max_misses T [frames], reset: one
    of :data:`QUERY_RESETS` (module docstring)."""

    tau_new: float = 0.4
    tau_old: float = 0.35
    max_misses: int = 5
    reset: str = "paper"

    def __post_init__(self) -> None:
        if not 0 <= self.tau_old <= self.tau_new <= 1 or self.max_misses < 1:
            raise ValueError(f"QueryLife: need 0 ≤ tau_old ≤ tau_new ≤ 1 and max_misses ≥ 1; got {self}")
        if self.reset not in QUERY_RESETS:
            raise ValueError(f"QueryLife: reset must be one of {', '.join(QUERY_RESETS)}, got {self.reset!r}")

    def may_start(self, score: float) -> bool:
        return score >= self.tau_new

    def observe(self, life: TrackLife, score: float | None, dt: float) -> None:
        life.score = 0.0 if score is None else score
        if score is None:
            life.since_update += dt
        else:
            life.hits += 1
            life.since_update = 0.0
        if life.score < self.tau_old:
            life.misses += 1
        elif self.reset == "paper" or life.score >= self.tau_new:
            life.misses = 0

    def is_dead(self, life: TrackLife) -> bool:
        return life.misses >= self.max_misses

    def is_reported(self, life: TrackLife) -> bool:
        return life.score >= self.tau_old


LIFE_RULES = {"hits": HitsAndAge, "mutr3d": QueryLife, "mutr3d_code": QueryLife}
"""Life rules by the name a tracker's ``life`` parameter takes."""
