"""``simrig view``: a run logged to a rerun recording, read back with rerun's own reader — every camera's
outline, ground truth, detections and tracks, the 3D view, and one timeline event per error of the run."""

import sys
from collections import Counter
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from simrig.cli import main
from simrig.pipeline.run import run_pipeline

rerun_chunk = pytest.importorskip("rerun.chunk")


def recording_rows(path):
    """entity path → (rows logged on the timeline, static rows, texts of its text logs)."""
    rows, static, texts = Counter(), Counter(), {}
    for chunk in rerun_chunk.RrdReader(path).stream().to_chunks():
        (static if chunk.is_static else rows)[chunk.entity_path] += chunk.num_rows
        batch = chunk.to_record_batch()
        if "TextLog:text" in batch.schema.names:
            texts.setdefault(chunk.entity_path, []).extend(t[0] for t in batch.column("TextLog:text").to_pylist())
    return rows, static, texts


@pytest.mark.parametrize(("tracker", "params"), [("sort", {}), ("saga", {"max_age_s": 0.05})])
def test_view_writes_every_camera_the_boxes_and_one_event_per_error(small_scenario, tmp_path, capsys, tracker,
                                                                    params):
    """saga that forgets a track after one frame switches identities (9 IDS in 3D and 2D here)."""
    frames = 12
    run = run_pipeline(small_scenario, tracker=tracker, params=params, out=tmp_path / "run", frames=frames)
    errors = pq.read_table(tmp_path / "run" / "scores" / run.label / "errors.parquet").to_pylist()
    assert main(["view", str(tmp_path / "run"), "--save", str(tmp_path / "v.rrd")]) == 0
    assert f"wrote     {tmp_path / 'v.rrd'}" in capsys.readouterr().out
    rows, static, texts = recording_rows(tmp_path / "v.rrd")
    for camera in run.report.metrics2d["per_camera"]:
        assert static[f"/cameras/{camera}/frame"] == 1  # no images: the image outline
        for layer in ("ground_truth", "detections", "tracks"):
            assert rows[f"/cameras/{camera}/{layer}"] == frames, (camera, layer)
    for layer in ("ground_truth", "detections", "ego"):
        assert rows[f"/world/{layer}"] == frames
    assert rows["/world/tracks"] == (frames if tracker == "saga" else 0)  # sort is a 2D tracker
    kinds = Counter(e["kind"] for e in errors)
    assert kinds["FN"] > 0 and (kinds["IDS"] > 0 or tracker == "sort"), kinds
    for kind in ("FN", "IDS", "FRAG"):
        assert rows[f"/events/{kind}"] == kinds[kind], kind
        assert len(texts.get(f"/events/{kind}", [])) == kinds[kind]
    switches = [e for e in errors if e["kind"] == "IDS"]
    for switch, text in zip(switches, texts.get("/events/IDS", []), strict=True):
        assert text.startswith(f"IDS {switch['dimension']}") and str(switch["actor_id"]) in text
        assert f"track {switch['previous_track_id']} → {switch['track_id']}" in text


def test_view_without_rerun_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun", None)
    assert main(["view", str(tmp_path), "--save", str(tmp_path / "v.rrd")]) == 2
    err = capsys.readouterr().err
    assert err == ("simrig: error: the viewer needs rerun-sdk: pip install 'simrig-mot[view]' "
                   "(or pip install rerun-sdk)\n")


def test_view_without_a_display_says_to_save(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert main(["view", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pass --save FILE.rrd" in err


def test_a_run_folder_with_several_trackers_needs_one_named(small_scenario, tmp_path, capsys):
    for tracker in ("sort", "saga"):
        run_pipeline(small_scenario, tracker=tracker, out=tmp_path / "run", frames=4)
    assert main(["view", str(tmp_path / "run"), "--save", str(tmp_path / "v.rrd")]) == 2
    assert "holds several trackers' output (saga, sort); choose one with --tracker" in capsys.readouterr().err
    assert main(["view", str(tmp_path / "run"), "--tracker", "saga", "--save", str(tmp_path / "v.rrd")]) == 0
    assert main(["view", str(tmp_path / "run"), "--tracker", "nope", "--save", str(tmp_path / "w.rrd")]) == 2
    assert "--tracker 'nope': no such run" in capsys.readouterr().err


def test_a_recording_is_never_written_into_what_it_shows_or_a_system_folder(small_scenario, tmp_path, capsys):
    # New-user trial: --save inside the run's dataset wrote a file into the input; /proc was a rerun traceback.
    run = run_pipeline(small_scenario, tracker="sort", out=tmp_path / "run", frames=3)
    tracks = tmp_path / "run" / "tracks" / run.label
    for save, expected in ((tmp_path / "run" / "dataset" / "x.rrd", "is inside the input"),
                           (tracks / "x.rrd", "is inside the input"),
                           (Path("/proc/x.rrd"), "is in the system folder /proc")):
        assert main(["view", str(tmp_path / "run"), "--save", str(save)]) == 2
        error = capsys.readouterr().err
        assert error.count("\n") == 1 and f"--save {str(save)!r} {expected}" in error, error
        assert not save.exists()
    assert main(["view", str(tmp_path / "run"), "--save", str(tmp_path / "run" / "view.rrd")]) == 0  # beside them
