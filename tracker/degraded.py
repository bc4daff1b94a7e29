"""A registered tracker made worse on purpose, for studies of what a tracker's errors cost: its tracks arrive late,
change identity at random, or carry noisy velocities.

``degraded`` wraps another registered tracker (``tracker``, built with its defaults) and changes only its output:

* ``latency_s`` [s]: the tracks returned at time t are those the wrapped tracker returned at the latest frame at
  or before t − latency_s (nothing before the first such frame): perception that reaches the planner late.
* ``identity_change_hz`` [1/s]: each track, each frame of duration Δt, takes a new identity with probability
  1 − exp(−rate·Δt) and keeps it until the next change: identity noise (fragmentation without a box error).
* ``velocity_sigma_mps`` [m/s]: white Gaussian noise of this σ added to each track's (vx, vy), per axis and frame.

Random draws come from ``reset``'s seed, one stream per cause, so switching one degradation off leaves the other's
draws as they were. The output is online: a wrapped semi-online tracker's ``finish()`` is not called.

>>> from simrig.trackers import create
>>> late = create("degraded", tracker="global_hungarian", latency_s=0.2)
>>> late.delay_s, late.inner.__class__.__name__
(0.2, 'KalmanTracker')
"""

from __future__ import annotations

import bisect
import dataclasses

import numpy as np

from simrig.seeding import stream_generator
from simrig.types import Rig, SensorFrame, Track

MAX_LATENCY_S = 60.0
"""[s] the longest latency taken."""


class DegradedTracker:
    """A tracker whose output is delayed, relabelled and given velocity noise (module docstring)."""

    def __init__(self, inner, *, latency_s: float, identity_change_hz: float, velocity_sigma_mps: float):
        self.inner = inner
        self.delay_s = float(latency_s)
        self.identity_change_hz = float(identity_change_hz)
        self.velocity_sigma_mps = float(velocity_sigma_mps)
        self.reset(rig=None, seed=None, inner=False)

    def reset(self, *, rig: Rig | None, seed: int | None = None, inner: bool = True) -> None:
        if inner:
            self.inner.reset(rig=rig, seed=seed)
        base = 0 if seed is None else int(seed)
        self._identity_rng = stream_generator("degraded_identity", base)
        self._velocity_rng = stream_generator("degraded_velocity", base)
        self._times: list[float] = []
        self._outputs: list[list[Track]] = []
        self._renamed: dict[int, int] = {}
        self._next_id = 1_000_000_000
        self._last_time: float | None = None

    def step(self, frame: SensorFrame) -> list[Track]:
        tracks = self._noisy(self.inner.step(frame), frame.timestamp)
        if self.delay_s == 0.0:
            return tracks
        self._times.append(frame.timestamp)
        self._outputs.append(tracks)
        latest = bisect.bisect_right(self._times, frame.timestamp - self.delay_s + 1e-9) - 1
        if latest < 0:
            return []
        del self._times[:latest], self._outputs[:latest]  # older outputs are never returned again
        return self._outputs[0]

    def _noisy(self, tracks: list[Track], timestamp: float) -> list[Track]:
        """``tracks`` relabelled and with velocity noise (the draws of one frame, in the tracks' order)."""
        dt = 0.0 if self._last_time is None else max(timestamp - self._last_time, 0.0)
        self._last_time = timestamp
        if self.identity_change_hz > 0 and tracks:
            changes = self._identity_rng.random(len(tracks)) < -np.expm1(-self.identity_change_hz * dt)
            for track, change in zip(tracks, changes, strict=True):
                if change:
                    self._renamed[track.track_id] = self._next_id
                    self._next_id += 1
            tracks = [dataclasses.replace(t, track_id=self._renamed.get(t.track_id, t.track_id)) for t in tracks]
        if self.velocity_sigma_mps > 0 and tracks:
            noise = self._velocity_rng.normal(0.0, self.velocity_sigma_mps, size=(len(tracks), 2))
            tracks = [t if t.box3d is None else dataclasses.replace(
                t, box3d=dataclasses.replace(t.box3d, vx=t.box3d.vx + dx, vy=t.box3d.vy + dy))
                for t, (dx, dy) in zip(tracks, noise.tolist(), strict=True)]
        return tracks


def degraded(*, tracker: str = "saga", latency_s: float = 0.0, identity_change_hz: float = 0.0,
             velocity_sigma_mps: float = 0.0) -> DegradedTracker:
    """The registered tracker ``tracker`` (its defaults) with its output degraded (module docstring): latency_s
    [s] in [0, 60], identity_change_hz [1/s] ≥ 0, velocity_sigma_mps [m/s] ≥ 0."""
    from .registry import create

    if tracker == "degraded":
        raise ValueError("parameter tracker must name another tracker, not this one")
    for name, value, top in (("latency_s", latency_s, MAX_LATENCY_S), ("identity_change_hz", identity_change_hz,
                             1e6), ("velocity_sigma_mps", velocity_sigma_mps, 1e6)):
        if not (0.0 <= float(value) <= top):
            raise ValueError(f"{name}={value!r} must be a number in [0, {top:g}]")
    return DegradedTracker(create(tracker), latency_s=latency_s, identity_change_hz=identity_change_hz,
                           velocity_sigma_mps=velocity_sigma_mps)
