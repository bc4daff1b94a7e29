"""Settings that could not take effect in a generated dataset, found by looking at what was generated.

A scenario can be valid and still ask for what the run cannot deliver: more vehicles than the window holds, a
perturbation aimed at an actor id that never appears, a window cut off by ``--frames``. These are warnings
(the dataset is what the simulation produced), printed by ``simrig generate`` and ``simrig run``.
"""

from __future__ import annotations

import numpy as np

from simrig.dataset import Dataset
from simrig.scenarios import Scenario
from simrig.scenarios.schema import windows_outside

DENSITY_SHORTFALL = 0.8
"""Below this fraction of ``traffic.vehicles`` on average, the requested density is called unreachable."""


def ineffective_settings(scenario: Scenario, dataset: Dataset) -> list[str]:
    """One message per setting of ``scenario`` that had no (or not its full) effect on ``dataset``."""
    messages = windows_outside(scenario, dataset.frame_count)
    truth = dataset.columns("ground_truth", ["frame", "actor_id"])
    ids = truth.column("actor_id").to_numpy()
    seen = set(np.unique(ids).tolist())
    for index, perturbation in enumerate(scenario.perturbations):
        missing = sorted(set(getattr(perturbation, "actors", ())) - seen)
        if missing:
            messages.append(f"perturbations.{index} ({perturbation.kind}): actor id(s) {missing} never appear in "
                            f"this run (ids seen: {min(seen, default='none')} … {max(seen, default='none')}); "
                            "no effect on them")
    wanted = scenario.traffic.vehicles
    if wanted > 0:
        per_frame = np.bincount(truth.column("frame").to_numpy(), minlength=dataset.frame_count)
        mean = float(per_frame.mean()) if len(per_frame) else 0.0
        if mean < DENSITY_SHORTFALL * wanted:
            radius = scenario.traffic.window_radius_m
            messages.append(f"traffic.vehicles = {wanted}, but only {mean:.1f} vehicles per frame on average "
                            f"(at most {int(per_frame.max(initial=0))}) fit in the {radius:g} m window: the "
                            "requested density is unreachable")
    return messages
