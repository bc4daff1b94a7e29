"""A dataset made from another dataset's world (only the sensor model rerun) is byte-identical to a full
generation: what lets the bench sweep detector settings without simulating or rendering again."""

from __future__ import annotations

from pathlib import Path

import pytest
from simrig.scenarios import load_scenario
from simrig.scenarios.overrides import with_setting

from simrig.dataset import Dataset
from simrig.errors import DatasetError
from simrig.pipeline.cache import cached_dataset
from simrig.pipeline.content_keys import world_key
from simrig.pipeline.generate import generate


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def scenarios(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "reuse.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 12\n'
        "[traffic]\nvehicles = 12\nwindow_radius_m = 90.0\nspawn_min_distance_m = 60.0\n"
        '[[perturbations]]\nkind = "cut_in"\nframes = [2, 10]\n'
        '[[perturbations]]\nkind = "occlude"\nnearest = 1\nframes = [3, 6]\n'
    )
    base = load_scenario(path)
    other = with_setting(with_setting(base, "sensor.detection.probability", 0.6), "perturbations.1.frames.1", 9)
    return base, other


@pytest.mark.parametrize("rendered", [True, False])
def test_a_detector_only_change_made_from_the_recorded_world_equals_a_full_generation(tmp_path, scenarios, rendered):
    base, other = (with_setting(s, "render.visibility", rendered) for s in scenarios)
    assert world_key(base, 3, None) == world_key(other, 3, None)
    source = Dataset.open(generate(base, seed=3, out=tmp_path / "base").path)
    full = generate(other, seed=3, out=tmp_path / "full").path
    reused = generate(other, seed=3, out=tmp_path / "reused", world_from=source).path
    assert _files(reused) == _files(full)
    assert _files(reused) != _files(source.path)  # the detector did change


def test_reruns_on_a_world_kept_in_memory_equal_a_full_generation(tmp_path, scenarios, monkeypatch):
    # explain reruns the sensor on one world dozens of times per process: the second and later passes are
    # served from memory, and must write what a full generation writes, each time.
    import simrig.pipeline.recorded_world as recorded

    base, other = scenarios
    source = Dataset.open(generate(base, seed=3, out=tmp_path / "base").path)
    full = _files(generate(other, seed=3, out=tmp_path / "full").path)
    first = _files(generate(other, seed=3, out=tmp_path / "first", world_from=source).path)
    assert recorded._memo is not None and recorded._memo[0][0] == source.manifest["manifest_sha256"]

    def no_reading(*args, **kwargs):
        raise AssertionError("the recorded world was read again")

    monkeypatch.setattr(Dataset, "ground_truth_frames", no_reading)
    for attempt in ("second", "third"):
        assert _files(generate(other, seed=3, out=tmp_path / attempt, world_from=source).path) == full
    assert first == full
    monkeypatch.undo()
    monkeypatch.setattr(recorded, "_memo", None)
    monkeypatch.setattr(recorded, "MEMO_FRAMES_LIMIT", 11)  # a world longer than the limit is not kept
    assert _files(generate(other, seed=3, out=tmp_path / "long", world_from=source).path) == full
    assert recorded._memo is None


def test_another_world_is_refused_naming_the_dataset(tmp_path, scenarios):
    base, _ = scenarios
    source = Dataset.open(generate(base, seed=3, out=tmp_path / "base").path)
    with pytest.raises(DatasetError, match="not the same world"):
        generate(with_setting(base, "rig.overlap_deg", 0.0), seed=3, out=tmp_path / "x", world_from=source)
    with pytest.raises(DatasetError, match="not the same world"):
        generate(base, seed=4, out=tmp_path / "y", world_from=source)


def test_the_cache_reuses_a_world_it_holds(tmp_path, scenarios, monkeypatch):
    base, other = scenarios
    first = cached_dataset(base, 1, None, tmp_path)
    import simrig.pipeline.generate as generation

    def no_simulation(*args, **kwargs):
        raise AssertionError("the traffic was simulated again")

    monkeypatch.setattr(generation, "TrafficWorld", no_simulation)
    second = cached_dataset(other, 1, None, tmp_path)
    assert second.path != first.path and second.manifest["world_key"] == first.manifest["world_key"]
