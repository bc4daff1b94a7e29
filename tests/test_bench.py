"""The bench end to end: local pool and Ray give the same bytes, rows match a direct run of the same cell,
a killed run resumes without redoing, losing or duplicating anything, and the report shows what the tables
hold."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from simrig.scenarios import load_scenario

from simrig.benchmark import BenchError, run_bench
from simrig.benchmark.parameters import apply_parameter
from simrig.pipeline.content_keys import dataset_key
from simrig.pipeline.generate import generate
from simrig.pipeline.track import run_tracker
from simrig.report import ReportError, write_report
from simrig.scoring import score

TESTS = Path(__file__).parent


@pytest.fixture(scope="module")
def smoke_local(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "smoke-local"
    return run_bench("smoke", out=out, workers=2)


@pytest.mark.slow  # the default pass stays under 10 minutes; CI runs the slow pass too
def test_smoke_local_and_ray_write_identical_tables(smoke_local, tmp_path):
    pytest.importorskip("ray")
    ray_run = run_bench("smoke", out=tmp_path / "smoke-ray", engine="ray", workers=2)
    assert ray_run.cells_run == smoke_local.cells_run == 10
    for name in ("results.parquet", "causes.parquet"):
        local_bytes = (smoke_local.out / name).read_bytes()
        assert local_bytes == (ray_run.out / name).read_bytes(), name
    assert pq.read_table(ray_run.results).num_rows == 38


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_results_have_one_row_per_point_and_tracker(smoke_local):
    rows = pq.read_table(smoke_local.results).to_pandas()
    # highway_surround6: 5 points × 2 seeds × (saga, global_hungarian); stereo_occluder: 3 × 2 × 3 trackers
    assert len(rows) == 5 * 2 * 2 + 3 * 2 * 3 == smoke_local.rows
    keys = rows[["scenario", "sweep", "value", "seed", "tracker"]].astype(str)
    assert not keys.duplicated().any()
    collab = rows[rows["tracker"] == "collabmot"]
    assert set(collab["scenario"]) == {"stereo_occluder"} and set(collab["scored"]) == {"left"}
    assert collab["3d_AMOTA"].isna().all() and collab["2d_HOTA"].notna().all()
    # a sweep value equal to the scenario's own setting is the base cell, reported under both
    base = rows[(rows["sweep"] == "") & (rows["scenario"] == "highway_surround6")]
    same = rows[(rows["sweep"] == "rig.overlap_deg") & (rows["value"] == 10.0)]
    assert list(base["cell"]) == list(same["cell"])
    assert np.array_equal(base["2d_HOTA"].to_numpy(), same["2d_HOTA"].to_numpy())
    # causes.parquet's totals are the rows' identity switches, row by row
    causes = pq.read_table(smoke_local.out / "causes.parquet").to_pandas()
    totals = causes[(causes["cause"] == "total") & (causes["kind"] == "IDS")]
    for row in rows.to_dict("records"):
        dimension, column = ("3d", "3d_IDS") if row["scored"] == "3d" else ("2d", "2d_IDSW")
        mine = totals[(totals["cell"] == row["cell"]) & (totals["tracker"] == row["tracker"])
                      & (totals["dimension"] == dimension) & (totals["sweep"] == row["sweep"])
                      & (totals["seed"] == row["seed"])]
        assert mine["count"].sum() == row[column]


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_row_equals_a_direct_run_of_its_cell(smoke_local, tmp_path):
    rows = pq.read_table(smoke_local.results).to_pandas()
    row = rows[(rows["scenario"] == "stereo_occluder") & (rows["sweep"] == "miss_probability")
               & (rows["value"] == 0.4) & (rows["seed"] == 1) & (rows["tracker"] == "saga")].iloc[0]
    scenario = load_scenario("stereo_occluder")
    scenario = scenario.model_copy(update={"sensor": scenario.sensor.model_copy(update={
        "detection": scenario.sensor.detection.model_copy(update={"probability": 0.6})})})
    assert dataset_key(scenario, 1, 40) == row["cell"] == dataset_key(
        apply_parameter(load_scenario("stereo_occluder"), "miss_probability", 0.4), 1, 40)
    generated = generate(scenario, seed=1, out=tmp_path / "dataset", frames=40)
    run = run_tracker(generated.path, "saga", tmp_path / "tracks")
    report = score(generated.path, run.out)
    assert row["3d_AMOTA"] == pytest.approx(report.metrics3d["overall"]["AMOTA"], abs=1e-12)
    assert row["3d_IDS"] == report.metrics3d["overall"]["IDS"]
    assert row["2d_HOTA"] == pytest.approx(report.metrics2d["overall"]["HOTA"], abs=1e-12)
    assert row["param.miss_probability"] == 0.4


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_rerun_skips_every_finished_cell(smoke_local):
    before = (smoke_local.out / "results.parquet").read_bytes()
    again = run_bench("smoke", out=smoke_local.out, workers=2)
    assert (again.cells_skipped, again.cells_run) == (10, 0)
    assert (smoke_local.out / "results.parquet").read_bytes() == before


TINY_SCENARIO = """extends = "highway_surround6"
frames = 25
[traffic]
vehicles = 12
window_radius_m = 100.0
spawn_min_distance_m = 70.0
[render]
visibility = false
"""
TINY_SUITE = """name = "tiny"
scenarios = ["tiny_scenario.toml"]
seeds = [0, 1, 2]
[[trackers]]
tracker = "saga"
[[trackers]]
tracker = "global_hungarian"
[[sweeps]]
parameter = "miss_probability"
values = [0.2, 0.3, 0.5]             # none is the scenario's own 0.1: 4 cells per seed
"""


def _tiny(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tiny_scenario.toml").write_text(TINY_SCENARIO)
    (folder / "tiny.toml").write_text(TINY_SUITE)
    return folder / "tiny.toml"


def _fragments(out: Path) -> dict[str, int]:
    return {str(path.relative_to(out)): path.stat().st_mtime_ns for path in (out / "fragments").glob("*/*.json")}


@pytest.mark.slow  # the default run stays under 10 minutes on 2 cores; CI runs it in the slow pass
def test_killed_run_resumes_without_redoing_losing_or_duplicating(tmp_path):
    suite = _tiny(tmp_path / "suite")
    reference = run_bench(suite, out=tmp_path / "reference", workers=2)
    assert reference.cells == 12
    out = tmp_path / "killed"
    command = [sys.executable, "-m", "simrig.cli", "bench", str(suite), "--out", str(out), "--workers", "1",
               "--quiet"]
    process = subprocess.Popen(command, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while len({Path(p).parent for p in _fragments(out) if out.exists()}) < 3:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no cell finished within 2 minutes"
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    done_before = _fragments(out)
    cells_before = {Path(p).parent.name for p in done_before}
    assert 3 <= len(cells_before) < 12, "the kill came too late to test resuming"
    assert not (out / "results.parquet").exists()  # nothing that looks finished
    assert json.loads((out / "bench.json").read_text())["complete"] is False

    resumed = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    complete_before = {cell for cell in cells_before if sum(Path(p).parent.name == cell for p in done_before) == 2}
    assert f"({len(complete_before)} finished earlier, {12 - len(complete_before)} run now)" in resumed.stdout
    after = _fragments(out)
    assert {path: after[path] for path in done_before} == done_before  # not one finished fragment redone
    assert len(after) == 12 * 2
    assert (out / "results.parquet").read_bytes() == reference.results.read_bytes()
    assert (out / "causes.parquet").read_bytes() == (reference.out / "causes.parquet").read_bytes()
    assert not list((out / "datasets").glob(".*partial*"))  # a generation cut by the kill was cleaned up


def test_failing_tracker_names_the_cell_and_keeps_finished_work(tmp_path, monkeypatch):
    suite = _tiny(tmp_path / "suite")
    text = suite.read_text().replace("seeds = [0, 1, 2]", "seeds = [0]")
    suite.write_text(text + '[[trackers]]\ntracker = "bench_trackers:Crashing"\n')
    monkeypatch.syspath_prepend(str(TESTS))
    with pytest.raises(BenchError, match=r"cell \w+ \(tiny_scenario, seed 0, 25 frames\), tracker "
                                         r"bench_trackers:Crashing: tracker 'bench_trackers:Crashing': frame 0: "
                                         r"step\(\) raised RuntimeError: this tracker always fails"):
        run_bench(suite, out=tmp_path / "out", workers=1, trust_file=True)
    assert not (tmp_path / "out" / "results.parquet").exists()


def test_cli_errors_are_one_line(tmp_path):
    from simrig.cli import main

    assert main(["bench", "nonexistent"]) == 2
    assert main(["report", str(tmp_path)]) == 2
    with pytest.raises(ReportError, match="has no bench.json"):
        write_report(tmp_path)


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_report_shows_the_tables(smoke_local, tmp_path):
    index = write_report(smoke_local.out, out=tmp_path / "report")
    text = index.read_text()
    rows = pq.read_table(smoke_local.results).to_pandas()
    base = rows[(rows["sweep"] == "")]
    for tracker in ("saga", "global_hungarian", "collabmot"):
        mine = base[base["tracker"] == tracker]
        hota = f"{mine['2d_HOTA'].mean():.3f}"
        assert f"| `{tracker}` | {mine['scenario'].nunique()} | {len(mine)} | {hota} |" in text
    for image in ("curves-miss_probability.png", "curves-rig_overlap_deg.png", "worst-bev.png", "worst-mosaic.png",
                  "curves-miss_probability-by-scenario.png"):
        assert f"]({image})" in text and (tmp_path / "report" / image).stat().st_size > 10_000
    # paired against the group's first tracker per (scenario, seed): the mean difference, then its interval
    pairs = base.pivot_table(index=["scenario", "seed"], columns="tracker", values=["2d_HOTA", "3d_IDS"])
    delta_hota = (pairs["2d_HOTA"]["global_hungarian"] - pairs["2d_HOTA"]["saga"]).to_numpy()
    delta_ids = (pairs["3d_IDS"]["global_hungarian"] - pairs["3d_IDS"]["saga"]).to_numpy()
    assert "Paired against `saga`" in text
    row = next(line for line in text.splitlines() if line.startswith("| `global_hungarian` | 4 | "))
    cells = [cell.strip() for cell in row.split("|")[1:-1]]
    assert cells[2].startswith(f"{delta_hota.mean():+.3f} [") and cells[5].startswith(f"{delta_ids.mean():+.1f} [")
    for cell in cells[2:]:
        low, high = (float(v) for v in cell.split("[")[1].split("]")[0].split(","))
        assert low <= float(cell.split()[0]) <= high, cell
        if 0.0 not in (low, high):  # a bound printed as ±0 can lie on either side of 0
            assert cell.endswith("n.s.") == (low < 0 < high), cell
    saga = rows[rows["tracker"] == "saga"].drop_duplicates("cell")
    worst = saga.sort_values(["3d_IDS", "2d_HOTA"], ascending=[False, True]).iloc[0]
    assert f"(cell `{worst['cell']}`)" in text
    # the report's own copies make it again
    assert f"Produced by `simrig bench smoke --out {smoke_local.out}` then `simrig report {smoke_local.out}" in text
    assert write_report(tmp_path / "report", out=tmp_path / "report").read_text() == text


def test_a_second_bench_in_the_same_folder_stops_at_once(tmp_path):
    from simrig.dataset.outputs import OutputPathError, folder_lock

    out = tmp_path / "busy"
    out.mkdir()
    with folder_lock(out, "simrig bench"), pytest.raises(OutputPathError, match="is in use by another simrig bench"):
        run_bench(_tiny(tmp_path / "suite"), out=out, workers=1)
    assert not (out / "fragments").exists()


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_2d_tracker_first_is_reported_under_a_2d_heading_with_its_real_switches(tmp_path):
    """A suite whose first tracker is `deepsort` with no camera, then `saga`: the bench labels deepsort
    `scored = 2d` with the 2D IDSW of a direct score, the report lists it under a 2D heading, chooses its
    worst cell by 2D switches, and has per-camera tables."""
    folder = tmp_path / "suite"
    folder.mkdir()
    (folder / "tiny_scenario.toml").write_text(TINY_SCENARIO.replace("frames = 25", "frames = 15"))
    (folder / "mixed.toml").write_text('name = "mixed"\nscenarios = ["tiny_scenario.toml"]\nseeds = [0]\n'
                                       '[[trackers]]\ntracker = "deepsort"\n[[trackers]]\ntracker = "saga"\n'
                                       '[[sweeps]]\nparameter = "miss_probability"\nvalues = [0.3]\n')
    run = run_bench(folder / "mixed.toml", out=tmp_path / "bench", workers=1, progress=False)
    rows = pq.read_table(run.results).to_pandas()
    assert set(rows.loc[rows["tracker"] == "deepsort", "scored"]) == {"2d"}
    assert set(rows.loc[rows["tracker"] == "saga", "scored"]) == {"3d"}
    base = rows[(rows["tracker"] == "deepsort") & (rows["sweep"] == "")].iloc[0]
    dataset = generate(load_scenario(folder / "tiny_scenario.toml"), seed=0, out=tmp_path / "d",
                       progress=False).path
    direct = score(dataset, run_tracker(dataset, "deepsort", tmp_path / "t", seed=0).out)
    assert direct.metrics3d is None and base["2d_IDSW"] == direct.metrics2d["overall"]["IDSW"]
    cameras = pq.read_table(run.out / "cameras.parquet").to_pandas()
    mine = cameras[(cameras["tracker"] == "deepsort") & (cameras["sweep"] == "")]
    assert {camera: values["IDSW"] for camera, values in direct.metrics2d["per_camera"].items()} == dict(
        zip(mine["camera"], mine["IDSW"], strict=True))
    text = write_report(run.out, out=tmp_path / "report").read_text()
    assert "### 2D trackers, scored in 2D over every camera" in text and "### 3D trackers" in text
    section = text.split("### 2D trackers")[1].split("###")[0]
    assert f"| `deepsort` | 1 | 1 | {base['2d_HOTA']:.3f} |" in section and "| `saga`" not in section
    assert "Per camera: 2D HOTA" in section and "`CAM_FRONT`" in section
    assert "The cell where `deepsort`" in text


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_suite_without_base_points_reports_its_curves_and_no_empty_tables(smoke_local, tmp_path):
    import shutil

    bench = tmp_path / "no-base"
    shutil.copytree(smoke_local.out, bench, ignore=shutil.ignore_patterns("datasets", "fragments"))
    rows = pq.read_table(bench / "results.parquet").to_pandas()
    pq.write_table(pa.Table.from_pandas(rows[rows["sweep"] != ""], preserve_index=False), bench / "results.parquet")
    text = write_report(bench, out=tmp_path / "report").read_text()
    assert "runs no scenario at its own settings (`base = false`)" in text
    assert "| tracker | scenarios | sequences |" not in text and "## Robustness curves" in text


def test_an_infinite_metric_survives_the_fragment_a_finished_cell_is_kept_in(tmp_path):
    """A drive where nothing ever closed in has least TTC inf, which JSON has no number for: the fragment keeps it
    (and NaN as null), and the results read it back as inf."""
    import math

    from simrig.benchmark.evaluate import METRIC_COLUMNS, Outcome
    from simrig.benchmark.results import _number, _read, write_fragment

    metrics = dict.fromkeys(METRIC_COLUMNS, 0.5) | {"drive_min_ttc_s": math.inf, "3d_AMOTA": math.nan}
    write_fragment(tmp_path, Outcome("cell", "key", metrics, (), 1.0, 1.0), 2.0)
    back = {name: _number(value) for name, value in _read(tmp_path, "cell", "key")["metrics"].items()}
    assert back["drive_min_ttc_s"] == math.inf and back["3d_AMOTA"] is None and back["2d_HOTA"] == 0.5
    with pytest.raises(ValueError, match="'many': not a number"):
        _number("many")
