"""Re-ID distances measured as a real model's are published (simrig.detector.reid), the appearance fit from a
log (simrig.detector.fit_appearance) and its one-line errors. Expected values come from arithmetic on hand-built
logs and from the settings the data was generated with."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from simrig.scenarios.schema import RigConfig, Scenario

from simrig.cli import main
from simrig.detector.fit_appearance import fit_appearance, read_embedding_log
from simrig.detector.reid import CROSS_CAMERA, VIEW_BINS_DEG, EmbeddingLog, reid_table
from simrig.geometry import project_boxes
from simrig.render.visibility import Visibility
from simrig.rig import build_rig
from simrig.seeding import RandomStreams
from simrig.sensor.model import SensorModel
from simrig.types import EgoPose, GroundTruthFrame


def _rotating_log(frames: int = 40, step_rad: float = 0.1) -> EmbeddingLog:
    """Two identities in 2D turning by ``step_rad`` a frame in camera 0, 90° apart; camera 1 sees identity 0
    0.5 rad further on at the same frames."""
    t = np.arange(frames)
    angle = np.concatenate([step_rad * t, np.pi / 2 + step_rad * t, step_rad * t + 0.5])
    return EmbeddingLog(np.zeros(3 * frames, dtype=np.int64), np.tile(t, 3),
                        np.repeat([0, 0, 1], frames), np.repeat([0, 1, 0], frames),
                        np.column_stack([np.cos(angle), np.sin(angle)]))


def test_reid_table_shares_are_the_arithmetic_of_a_hand_built_log():
    rows = {row.gaps: row for row in reid_table(_rotating_log())}
    # d = 0.5·(1 − cos(0.1·g)) ≤ 0.2 ⇔ g ≤ 9, ≤ 0.25 ⇔ g ≤ 10; in 40 frames gap g has 40 − g pairs per
    # (identity, camera) track, and there are three tracks
    pairs = {g: 40 - g for g in range(6, 16)}
    band = rows["6-15"]
    assert band.same_pairs == 3 * sum(pairs.values())
    assert band.same_below[0] == pytest.approx(sum(pairs[g] for g in range(6, 10)) / sum(pairs.values()))
    assert band.same_below[1] == pytest.approx(sum(pairs[g] for g in range(6, 11)) / sum(pairs.values()))
    assert rows["1"].same_below == (1.0, 1.0)
    assert rows["1"].auc == 1.0  # every same pair (d = 0.0025) is closer than every different one (d ≥ 0.45)
    assert rows["1"].different_below == (0.0, 0.0)
    assert rows["16-30"].same_below[0] == 0.0  # g ≥ 16 turns 1.6 rad: d > 0.5
    cross = rows[CROSS_CAMERA]
    assert cross.same_pairs == 40 and cross.same_median == pytest.approx(0.5 * (1 - np.cos(0.5)))
    assert rows["121-240"].same_pairs == 0 and np.isnan(rows["121-240"].auc)


RIG = build_rig(RigConfig(preset="stereo"))


def _sensor_log(settings: dict, seed: int, actors: int = 40, frames: int = 200) -> EmbeddingLog:
    """Embeddings the sensor model gives ``actors`` cars 20 m ahead of a stereo pair, every frame detected by both
    cameras."""
    scenario = Scenario.model_validate({
        "name": "t", "render": {"visibility": False}, "traffic": {"class_mix": {"car": 1.0}},
        "sensor": {"detection": {"probability": 1.0}, "clutter": {"rate_per_frame": 0.0},
                   "embedding": {"occlusion_sigma": 0.0, **settings}}})
    boxes = np.zeros((actors, 9))
    boxes[:, 0] = RIG.cameras[0].position[0] + 20.0
    boxes[:, 3:6] = 4.5, 1.8, 1.5
    ego = EgoPose(0.0, 0.0, 0.0, 0.0)
    model = SensorModel(scenario, RIG, RandomStreams(seed))
    projection = project_boxes(boxes, RIG, ego)
    visibility = Visibility.unmeasured(projection)
    assert projection.in_view.all()
    vectors = []
    for frame in range(frames):
        state = GroundTruthFrame(frame=frame, timestamp=frame / 10.0, ego=ego, actor_ids=np.arange(actors),
                                 classes=np.full(actors, "car", dtype=object), boxes=boxes)
        vectors.append(model.observe(state, projection, visibility).batch.embeddings.astype(float).reshape(-1, 12))
    rows = frames * 2 * actors  # per frame: camera 0's actors, then camera 1's
    return EmbeddingLog(np.zeros(rows, dtype=np.int64), np.repeat(np.arange(frames), 2 * actors),
                        np.tile(np.repeat([0, 1], actors), frames), np.tile(np.arange(actors), 2 * frames),
                        np.concatenate(vectors))


TRUE = {"dimension": 12, "sigma": 0.45, "drift_sigma": 0.63, "drift_time_s": 0.73, "slow_drift_sigma": 0.68,
        "slow_drift_time_s": 10.8, "lookalike_weight": 0.3}
TOLERANCE = {"sigma": 0.10, "drift_sigma": 0.15, "drift_time_s": 0.20, "slow_drift_sigma": 0.25}
"""Relative tolerances of the round trip (40 cars seen by two cameras, 400 frames at 10 Hz); the dimension within
±2 and the slow drift's correlation time within a factor 2. Two cameras see the same drifts at one instant, so
only the gaps along the log tell a slow drift from a lasting look: a 40 s log holds nearly four of its 10.8 s (a
20 s one left the slow drift's size 30 % off on one seed in 20)."""
ROUND_TRIP_FRAMES = 400


def _check_round_trip(seed: int) -> None:
    fit = fit_appearance(_sensor_log(TRUE, seed, frames=ROUND_TRIP_FRAMES), 10.0).settings
    assert abs(fit["dimension"] - TRUE["dimension"]) <= 2, (seed, fit)
    for name, tolerance in TOLERANCE.items():
        assert fit[name] == pytest.approx(TRUE[name], rel=tolerance), (seed, name, fit)
    assert TRUE["slow_drift_time_s"] / 2 <= fit["slow_drift_time_s"] <= 2 * TRUE["slow_drift_time_s"], (seed, fit)


@pytest.mark.parametrize("seed", [0, 1])
def test_fit_recovers_the_appearance_settings_the_data_was_made_with(seed):
    _check_round_trip(seed)


@pytest.mark.slow
def test_fit_recovers_the_appearance_settings_over_20_seeds():
    for seed in range(100, 120):
        _check_round_trip(seed)


def _write_log(path: Path, log: EmbeddingLog, embeddings: list | None = None, identity=None) -> Path:
    pq.write_table(pa.table({
        "frame": log.frame, "camera": [f"cam{c}" for c in log.camera],
        "identity": log.identity if identity is None else identity,
        "embedding": embeddings if embeddings is not None else [list(map(float, e)) for e in log.embeddings]}), path)
    return path


def test_fit_command_writes_settings_a_scenario_accepts(tmp_path, capsys):
    log = _write_log(tmp_path / "log.parquet", _sensor_log(TRUE, 3, actors=30, frames=120))
    assert main(["detector", "fit", "--embeddings", str(log), "--out", str(tmp_path / "fit.toml")]) == 0
    assert "mean cos same" in capsys.readouterr().out
    import tomllib

    table = tomllib.loads((tmp_path / "fit.toml").read_text())["sensor"]
    scenario = Scenario.model_validate({"name": "t", "sensor": table})
    assert scenario.sensor.embedding.dimension == pytest.approx(12, abs=2)
    assert read_embedding_log(log).embeddings.shape == (2 * 30 * 120, 12)


def test_a_small_log_still_gives_settings_within_the_schema(tmp_path, capsys):
    """Five identities over 30 frames: the fit is poor, says so, and writes settings a scenario accepts."""
    log = _write_log(tmp_path / "small.parquet", _sensor_log(TRUE, 4, actors=5, frames=30))
    assert main(["detector", "fit", "--embeddings", str(log), "--out", str(tmp_path / "fit.toml")]) == 0
    assert "WARNING: only 5 identities" in capsys.readouterr().out
    import tomllib

    Scenario.model_validate({"name": "t", "sensor": tomllib.loads((tmp_path / "fit.toml").read_text())["sensor"]})


@pytest.mark.parametrize(("case", "expected"), [
    ("dimensions", "column embedding: row 0 has 12 values but row 7 has 11; one length expected"),
    ("nan", "column embedding: row 3 holds NaN or infinity"),
    ("one-identity", "column identity: only one identity"),
    ("zero", "column embedding: row 5 is all zeros"),
    ("missing-column", "missing column(s) identity"),
    ("not-parquet", "not a Parquet table"),
    ("fifo", "not a regular file"),
])
def test_bad_embedding_logs_are_one_line(case, expected, tmp_path, capsys):
    log = _sensor_log(TRUE, 0, actors=4, frames=10)
    vectors = [list(map(float, e)) for e in log.embeddings]
    path = tmp_path / f"{case}.parquet"
    if case == "dimensions":
        vectors[7] = vectors[7][:11]
        _write_log(path, log, vectors)
    elif case == "nan":
        vectors[3][0] = float("nan")
        _write_log(path, log, vectors)
    elif case == "zero":
        vectors[5] = [0.0] * 12
        _write_log(path, log, vectors)
    elif case == "one-identity":
        _write_log(path, log, identity=np.zeros(len(log), dtype=np.int64))
    elif case == "fifo":
        os.mkfifo(path)
    elif case == "missing-column":
        pq.write_table(pa.table({"frame": log.frame, "camera": log.camera, "embedding": vectors}), path)
    else:
        path.write_text("frame,camera\n1,2\n")
    code = main(["detector", "fit", "--embeddings", str(path), "--out", str(tmp_path / "fit.toml")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("simrig: error: "), lines
    assert expected in lines[0] and path.name in lines[0], lines[0]
    assert not (tmp_path / "fit.toml").exists()


def test_fit_refuses_to_write_over_its_own_log(tmp_path, capsys):
    log = _write_log(tmp_path / "log.parquet", _sensor_log(TRUE, 0, actors=4, frames=10))
    before = log.read_bytes()
    code = main(["detector", "fit", "--embeddings", str(log), "--out", str(log)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "--out" in lines[0] and "input" in lines[0], lines
    assert log.read_bytes() == before


def test_fit_never_writes_through_a_symbolic_link(tmp_path, capsys):
    log = _write_log(tmp_path / "log.parquet", _sensor_log(TRUE, 0, actors=4, frames=10))
    victim = tmp_path / "victim.txt"
    victim.write_text("mine")
    (tmp_path / "link.toml").symlink_to(victim)
    code = main(["detector", "fit", "--embeddings", str(log), "--out", str(tmp_path / "link.toml")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "symbolic link" in lines[0], lines
    assert victim.read_text() == "mine"


def test_two_synchronised_cameras_see_a_car_at_least_as_alike_as_one_camera_a_frame_later(tmp_path):
    """``simrig detector measure`` on ``stereo_occluder``: the same car, the same instant, cameras 0.54 m apart
    (rays < 5° apart) has a median distance no larger than 1.5 × one camera's gap-1 median — what two nearly
    identical images must give, whatever the features. (Before the drifts were the actor's, each camera had its
    own, and this ratio was above 4.)"""
    from simrig.scenarios import load_scenario

    from simrig.detector.measure import measure
    from simrig.pipeline.generate import generate

    generate(load_scenario("stereo_occluder"), seed=100, frames=120, out=tmp_path / "ds")
    rows = {row.gaps: row for row in measure(tmp_path / "ds").reid}
    cross, gap1 = rows[CROSS_CAMERA], rows["1"]
    assert cross.same_pairs >= 100 and gap1.same_pairs >= 100
    assert cross.same_median <= 1.5 * gap1.same_median
    assert rows["other camera, 0.54 m apart"].same_pairs == cross.same_pairs  # the stereo baseline, every pair
    bins = [rows[f"other camera, rays {lo:g}-{hi:g} deg"].same_pairs for lo, hi in VIEW_BINS_DEG]
    assert sum(bins) == cross.same_pairs and sum(bins[:2]) >= 0.9 * cross.same_pairs  # 0.54 m: rays < 5° apart
