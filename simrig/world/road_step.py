"""highway-env's ``Road.step`` with the collision loop's spherical pre-check done for every pair at once.

``Road.step`` moves every vehicle, then asks each vehicle about every later vehicle and every road object
(``handle_collisions``), and highway-env's first test there (``RoadObject._is_colliding``) is a spherical one:
a pair whose centres are further apart than ``(diagonal₁ + diagonal₂) / 2 + speed₁ · dt`` cannot collide, and
nothing else happens for it. With 40 vehicles that is about 800 Python calls per simulation step, almost all of
which stop there. :func:`step_road` does that test for every pair in one numpy expression, with a margin
(:data:`MARGIN_M`, and ``|speed₁|`` for ``speed₁``) that can only keep more pairs, and calls highway-env's own
``handle_collisions`` on the pairs kept, in highway-env's order: every pair that could collide gets the exact
test it always got, so the same pairs collide and datasets keep their bytes.
"""

from __future__ import annotations

import numpy as np

MARGIN_M = 1e-6
"""[m] added to the spherical test's reach, so that rounding (the distance is computed differently from
highway-env's ``np.linalg.norm``) can only keep a pair, never drop one."""


def step_road(road, dt: float) -> None:
    """One simulation step of highway-env ``road`` of ``dt`` [s], as ``Road.step`` does it (module docstring)."""
    vehicles, objects = road.vehicles, road.objects
    for vehicle in vehicles:
        vehicle.step(dt)
    if not vehicles:
        return
    everything = vehicles + objects
    positions = np.array([thing.position for thing in everything], dtype=float).reshape(-1, 2)
    half_diagonals = np.array([thing.diagonal for thing in everything], dtype=float) / 2.0
    travel = np.abs(np.array([vehicle.speed for vehicle in vehicles], dtype=float)) * dt
    n = len(vehicles)
    gaps = positions[None, :, :] - positions[:n, None, :]
    reach = half_diagonals[:n, None] + half_diagonals[None, :] + travel[:, None] + MARGIN_M
    later = np.arange(len(everything))[None, :] > np.arange(n)[:, None]  # later vehicles, then every object
    apart = np.hypot(gaps[..., 0], gaps[..., 1]) > reach  # highway-env's own comparison: a NaN is never apart
    first, second = np.nonzero(later & ~apart)  # row-major: highway-env's loop order
    for i, j in zip(first.tolist(), second.tolist(), strict=True):
        vehicles[i].handle_collisions(everything[j], dt)
