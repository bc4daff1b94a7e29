"""Hypothesis strategies for simrig scenarios: small, valid, quick to run (seconds each).

>>> from hypothesis import given
>>> @given(scenarios(max_frames=8))
... def test_drawn(scenario):
...     assert 1 <= scenario.frames <= 8

Limits keep a drawn scenario cheap: at most ``max_frames`` frames at 10 Hz and ``max_vehicles`` vehicles in a
120 m window, and the visibility render off unless ``render=True`` (occlusion then comes only from scheduled
``occlude`` windows, never from other vehicles). Everything shrinks towards fewer frames, fewer vehicles, less
noise and no perturbations.
"""

from __future__ import annotations

from hypothesis import strategies as st

from simrig.scenarios.schema import Scenario

RIGS = ("surround6", "stereo")

seeds = st.integers(min_value=0, max_value=2**31 - 1)
"""Scenario seeds (every random stream of a generation comes from one): ``run_tracker(..., seed=draw(seeds))``."""


@st.composite
def windows(draw, frames: int) -> list[int]:
    """An inclusive frame window ``[a, b]`` inside ``frames`` frames."""
    start = draw(st.integers(0, frames - 1))
    return [start, draw(st.integers(start, frames - 1))]


@st.composite
def perturbations(draw, frames: int, kinds: tuple[str, ...] = ("occlude", "miss_burst")) -> dict:
    """One scheduled perturbation as a scenario table: ``occlude`` (the nearest 1-2 actors hidden from every
    camera) or ``miss_burst`` (the detector misses everything with a probability)."""
    kind = draw(st.sampled_from(kinds))
    table = {"kind": kind, "frames": draw(windows(frames))}
    if kind == "occlude":
        table["nearest"] = draw(st.integers(1, 2))
    elif kind == "miss_burst":
        table["probability"] = draw(st.floats(0.1, 1.0))
    return table


@st.composite
def scenarios(draw, *, rigs: tuple[str, ...] = RIGS, max_frames: int = 15, max_vehicles: int = 8,
              max_perturbations: int = 2, noise: bool = True, clutter: bool = True, render: bool = False,
              perfect: bool = False) -> Scenario:
    """A valid :class:`~simrig.scenarios.schema.Scenario`. ``perfect`` draws a detector that sees every actor in view
    exactly (no noise, misses, clutter or perturbations)."""
    frames = draw(st.integers(2, max_frames))
    rig = draw(st.sampled_from(rigs))
    rig_table: dict = {"preset": rig}
    if rig == "surround6":
        rig_table["overlap_deg"] = draw(st.floats(0.0, 30.0))
    elif rig == "stereo":
        rig_table["baseline_m"] = draw(st.sampled_from([0.54, 0.14]))
    sensor: dict = {}
    if perfect:
        sensor = {"detection": {"probability": 1.0, "min_visible_fraction": 0.0, "full_visible_fraction": 1e-6,
                                "full_truncation": 0.999, "max_truncation": 1.0, "full_range_m": 1000.0,
                                "max_range_m": 1001.0},
                  "box2d": {"relative_sigma": 0.0},
                  "box3d": {"depth_sigma_m": 0.0, "depth_sigma_per_m": 0.0, "lateral_sigma_m": 0.0},
                  "score": {"base": 0.9, "gain": 0.1, "sigma": 0.0}, "clutter": {"rate_per_frame": 0.0}}
    else:
        if noise:
            sensor["box2d"] = {"relative_sigma": draw(st.floats(0.0, 0.05))}
        sensor["detection"] = {"probability": draw(st.floats(0.7, 1.0))}
        sensor["clutter"] = {"rate_per_frame": draw(st.floats(0.0, 1.0)) if clutter else 0.0}
    raw = {
        "name": "drawn",
        "description": "drawn by simrig.testing.strategies.scenarios",
        "frames": frames,
        "traffic": {"lanes": draw(st.integers(2, 4)), "vehicles": draw(st.integers(1, max_vehicles)),
                    "window_radius_m": 120.0, "spawn_min_distance_m": 80.0},
        "rig": rig_table,
        "render": {"visibility": render},
        "sensor": sensor,
        "perturbations": [] if perfect else draw(st.lists(perturbations(frames), max_size=max_perturbations)),
    }
    return Scenario.model_validate(raw)
