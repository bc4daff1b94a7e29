"""Building blocks shared by the reference trackers' factories: parameters in, parts out."""

from __future__ import annotations

from .cost_models import cost_model
from .life import LIFE_RULES, HitsAndAge, QueryLife
from .motion import KalmanConfig


def _build_cost(cost: str, gate: float | None, **extra):
    """The cost model ``cost`` with ``gate`` (its default when None) and any extra settings."""
    params = dict(extra)
    if gate is not None:
        params["gate"] = float(gate)
    return cost_model(cost, **params)


def build_life(life: str, *, min_hits: int, max_age_s: float, min_score: float = 0.0) -> HitsAndAge | QueryLife:
    """``life='hits'``: :class:`HitsAndAge` with these settings; ``'mutr3d'``: :class:`QueryLife` as MUTR3D's
    §3.4 says (τ_new 0.4, τ_old 0.35, dead after T = 5 successive frames below τ_old); ``'mutr3d_code'``: the
    same with the public code's miss count, reset only at a score ≥ τ_new."""
    if life not in LIFE_RULES:
        raise ValueError(f"unknown life rule {life!r}; known: {', '.join(LIFE_RULES)}")
    if life == "hits":
        return HitsAndAge(min_hits=int(min_hits), max_age_s=float(max_age_s), min_score=float(min_score))
    return QueryLife(reset="paper" if life == "mutr3d" else "tau_new")


def build_kalman(measurement_variance: float) -> KalmanConfig:
    """AB3DMOT's filter with measurement variance R = ``measurement_variance`` · I [m², rad²]."""
    return KalmanConfig(measurement_variance=float(measurement_variance))


def kalman_tracker_parts(*, cost: str, gate: float | None, life: str, min_hits: int, max_age_s: float,
                         measurement_variance: float, score_threshold: float, motion_compensation: bool = True,
                         **cost_extra) -> dict:
    """Keyword arguments of :class:`~simrig.trackers.kalman_tracker.KalmanTracker` every reference tracker shares:
    the cost model, the life rule, the filter settings, the score threshold and motion compensation (tracks
    predicted to each detection's capture time)."""
    return {
        "motion_compensation": bool(motion_compensation),
        "cost": _build_cost(cost, gate, **cost_extra),
        "life": build_life(life, min_hits=min_hits, max_age_s=max_age_s),
        "kalman": build_kalman(measurement_variance),
        "score_threshold": float(score_threshold),
    }
