"""Temporally correlated random processes kept per actor (per camera, or shared by all cameras).

An actor's state lives as long as the actor is in the frame's actor list; an actor that leaves the world
and a new actor that enters start from the stationary distribution. Every process draws exactly one set
of numbers per actor and frame, whether or not the actor is seen, so the draws of one process never
depend on another's settings.
"""

from __future__ import annotations

import math

import numpy as np


def ar1_coefficient(period_s: float, correlation_time_s: float) -> float:
    """φ = exp(−Δt / τ): the lag-1 correlation of an Ornstein–Uhlenbeck process with correlation time τ [s]
    sampled every Δt [s]; 0 for τ = 0 (white noise).

    >>> round(ar1_coefficient(0.1, 1.0), 4), round(ar1_coefficient(0.05, 1.0) ** 2, 4), ar1_coefficient(0.1, 0.0)
    (0.9048, 0.9048, 0.0)
    """
    return math.exp(-period_s / correlation_time_s) if correlation_time_s > 0 else 0.0


class ActorState:
    """Persistent float state of shape ``shape`` per actor id (e.g. ``(C, 9)``: nine values per camera; sorted
    ids, vectorised look-up)."""

    def __init__(self, shape: tuple[int, ...]):
        self.ids = np.empty(0, dtype=np.int64)
        self.values = np.empty((0, *shape))

    def recall(self, actor_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(values (N, *shape), known (N,))`` for the frame's actors; unknown actors get zeros."""
        index = np.searchsorted(self.ids, actor_ids)
        index = np.minimum(index, max(len(self.ids) - 1, 0))
        known = (self.ids[index] == actor_ids) if len(self.ids) else np.zeros(len(actor_ids), dtype=bool)
        values = np.zeros((len(actor_ids), *self.values.shape[1:]))
        values[known] = self.values[index[known]]
        return values, known

    def keep(self, actor_ids: np.ndarray, values: np.ndarray) -> None:
        """Remember ``values`` for exactly the frame's actors (actors no longer present are forgotten)."""
        order = np.argsort(actor_ids, kind="stable")
        self.ids = np.asarray(actor_ids, dtype=np.int64)[order]
        self.values = np.asarray(values, dtype=float).reshape(len(actor_ids), *self.values.shape[1:])[order]


def _known(known: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``known`` ``(N,)`` broadcast against ``values`` ``(N, …)``."""
    return known.reshape(-1, *([1] * (values.ndim - 1)))


class GaussMarkov:
    """Unit-variance AR(1) processes with coefficient φ per last-axis column (``width`` = len(φ) per actor, or
    ``(…, width)`` per actor, e.g. per camera): x ← φ·x + √(1 − φ²)·z for known actors, x ← z for new ones (the
    stationary distribution). The shape per actor is fixed by the first step."""

    def __init__(self, phi: np.ndarray):
        self.phi = np.asarray(phi, dtype=float)
        self.state: ActorState | None = None

    def step(self, actor_ids: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Advance one frame with standard normal innovations ``z`` ``(N, …, width)``; returns the new state."""
        if self.state is None:
            self.state = ActorState(z.shape[1:])
        previous, known = self.state.recall(actor_ids)
        advanced = self.phi * previous + np.sqrt(1.0 - self.phi**2) * z
        values = np.where(_known(known, z), advanced, z)
        self.state.keep(actor_ids, values)
        return values


class TwoStateMarkov:
    """A per-actor on/off chain with stationary 'on' probability ``p`` and mean 'on' stay ``mean_on_s`` [s]:
    per frame period Δt, on → off with q = min(1, Δt / mean_on_s) and off → on with r = p·q / (1 − p), so
    stays are geometric with mean mean_on_s / Δt frames at any frame rate. ``mean_on_s`` = 0 draws the state
    afresh every frame (r = p, q = 1 − p). New actors start on with probability ``p``."""

    def __init__(self, p: float, mean_on_s: float, period_s: float):
        self.p = float(p)
        if mean_on_s > 0 and p > 0:
            self.q = min(1.0, period_s / mean_on_s)
            self.r = min(1.0, p * self.q / (1.0 - p))
        else:
            self.q, self.r = 1.0 - p, p
        self.state: ActorState | None = None

    def step(self, actor_ids: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Advance one frame with uniform draws ``u`` ``(N,)`` (or ``(N, …)``: several chains per actor, e.g.
        one per camera); returns the new on/off states, shaped like ``u``. The shape per actor is fixed by the
        first step."""
        if self.state is None:
            self.state = ActorState(u.shape[1:])
        previous, known = self.state.recall(actor_ids)
        on = previous > 0.5
        advanced = np.where(on, u >= self.q, u < self.r)
        values = np.where(_known(known, u), advanced, u < self.p)
        self.state.keep(actor_ids, values.astype(float))
        return values
