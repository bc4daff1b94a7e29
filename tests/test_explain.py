"""``simrig explain``: Shapley shares of the gap to a perfect sensor, from counterfactual sensor reruns.

What a user relies on: the shares add up (efficiency), a cause the scenario lacks costs exactly nothing, a
planted cause takes the loss it caused, and bad input is one line.
"""

from __future__ import annotations

import json
import math

import pyarrow.parquet as pq
import pytest
from simrig.scenarios import load_scenario

from simrig.cli import main
from simrig.explain import ExplainError, explain
from simrig.pipeline.run import run_pipeline


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A saga run of a small scenario without clutter or ghosts (false positives are absent from it)."""
    folder = tmp_path_factory.mktemp("explain")
    path = folder / "small.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 30\n'
        "[traffic]\nvehicles = 18\nwindow_radius_m = 100.0\nspawn_min_distance_m = 70.0\n"
        "[sensor.detection]\nprobability = 0.85\n"
        "[sensor.clutter]\nrate_per_frame = 0.0\n"
        "[sensor.ghosts]\nbirth_rate_hz = 0.0\n"
    )
    run_pipeline(load_scenario(path), seed=1, tracker="saga", out=folder / "run")
    return folder / "run"


@pytest.fixture(scope="module")
def explained(run_folder):
    return explain(run_folder, causes=["occlusion", "random_misses", "false_positives", "cross_camera"],
                   metrics=["AMOTA", "HOTA", "IDS", "FN", "FRAG"], workers=1)


def test_exact_shares_add_up_to_the_gap_between_perfect_and_actual(explained):
    document = explained.document
    assert document["mode"] == "exact" and document["coalitions"] == 2**4
    gaps = 0
    for name, entry in document["metrics"].items():
        gap = entry["perfect"] - entry["actual"]
        assert math.isclose(sum(entry["shares"].values()), gap, rel_tol=0, abs_tol=1e-9), name
        assert abs(entry["residual"]) <= 1e-9
        gaps += gap != 0
    assert gaps >= 3  # the sensor's imperfections do cost this tracker something
    # the actual value is the run's own score (same dataset, same deterministic tracker)
    score = json.loads((run_folder_of(explained) / "scores/saga/score.json").read_text())
    assert document["metrics"]["AMOTA"]["actual"] == pytest.approx(score["3d"]["overall"]["AMOTA"], abs=1e-12)
    assert document["metrics"]["HOTA"]["actual"] == pytest.approx(score["2d"]["overall"]["HOTA"], abs=1e-12)


def run_folder_of(result):
    return result.out.parents[1]


def test_a_cause_absent_from_the_scenario_gets_exactly_zero(explained):
    document = explained.document
    for entry in document["metrics"].values():
        assert entry["shares"]["false_positives"] == 0.0
    # and it is not among the groups explained by default
    assert "false_positives" not in explain_groups(run_folder_of(explained))


def explain_groups(run_dir):
    from simrig.scenarios.schema import scenario_from_record

    from simrig.dataset import Dataset
    from simrig.sensor.groups import present_groups

    dataset = Dataset.open(run_dir / "dataset")
    return present_groups(scenario_from_record(dataset.scenario), len(dataset.rig.cameras))


def test_outputs_and_verdicts_are_written(explained):
    out = explained.out
    assert json.loads((out / "explain.json").read_text()) == explained.document
    assert len(explained.plots) == 5 and all(p.stat().st_size > 1000 for p in explained.plots)
    verdicts = pq.read_table(out / "verdicts.parquet").to_pylist()
    errors = pq.read_table(run_folder_of(explained) / "scores/saga/errors.parquet")
    assert len(verdicts) == sum(kind in ("FN", "IDS", "FRAG") for kind in errors.column("kind").to_pylist())
    counts = explained.document["verdicts"]["3d"]["FN"]
    assert counts["total"] == sum(1 for v in verdicts if v["dimension"] == "3d" and v["kind"] == "FN")
    assert counts["occlusion"] == sum(1 for v in verdicts if v["dimension"] == "3d" and v["kind"] == "FN"
                                      and "occlusion" in v["fixed_by"])
    assert counts["false_positives"] == 0  # removing an absent cause fixes nothing


def test_sampled_mode_states_an_interval_and_still_adds_up(run_folder, tmp_path):
    import shutil

    shutil.copytree(run_folder, tmp_path / "run")  # its own copy: explaining only HOTA removes the other plots
    result = explain(tmp_path / "run", causes=["occlusion", "localisation", "cross_camera"], metrics=["HOTA"],
                     samples=4, workers=1)
    entry = result.document["metrics"]["HOTA"]
    assert result.document["mode"] == "sampled" and set(entry["ci95"]) == {"occlusion", "localisation",
                                                                            "cross_camera"}
    assert all(value >= 0 for value in entry["ci95"].values())
    # each permutation's marginals telescope to perfect − actual, so the sampled mean does too
    assert sum(entry["shares"].values()) == pytest.approx(entry["perfect"] - entry["actual"], abs=1e-9)


def test_two_permutations_give_shares_without_an_interval_not_a_crash(run_folder, tmp_path):
    # New-user trial: --samples 2 (one order and its reverse: one antithetic pair) made an infinite half-width
    # that the JSON writer refused, after every counterfactual had run.
    import shutil

    shutil.copytree(run_folder, tmp_path / "run")
    result = explain(tmp_path / "run", causes=["occlusion", "localisation"], metrics=["HOTA"], samples=2, workers=1)
    entry = json.loads((result.out / "explain.json").read_text())["metrics"]["HOTA"]
    assert entry["ci95"] == {"occlusion": None, "localisation": None}
    assert sum(entry["shares"].values()) == pytest.approx(entry["perfect"] - entry["actual"], abs=1e-9)
    assert "no confidence interval, --samples 3 or more gives one" in result.table and "±" not in result.table


def test_explaining_again_leaves_only_the_plots_of_the_metrics_it_explains(explained, tmp_path):
    # New-user trial: a second explain with fewer metrics left the first one's waterfalls beside the new JSON.
    import shutil

    copy = tmp_path / "run"
    shutil.copytree(run_folder_of(explained), copy)  # its counterfactual cache too: no sensor reruns
    for name in ("AMOTA", "FN", "FRAG"):  # an earlier explanation's plots (other tests may explain this run too)
        (copy / "explain" / "saga" / f"waterfall-{name}.png").write_bytes(b"an earlier plot")
    again = explain(copy, causes=["occlusion", "random_misses", "false_positives", "cross_camera"],
                    metrics=["HOTA", "IDS"], workers=1)
    assert sorted(p.name for p in again.out.glob("waterfall-*.png")) == ["waterfall-HOTA.png", "waterfall-IDS.png"]
    assert sorted(again.document["metrics"]) == ["HOTA", "IDS"]


def test_planted_occlusion_takes_the_identity_switch_and_miss_loss_of_sort(tmp_path):
    """A perfect detector but for one scheduled 20-frame occlusion of one actor: ``sort`` (max_age 1) loses
    the track and starts a new one; removing the occlusion takes ≥ 90 % of the IDS and FN loss."""
    path = tmp_path / "planted.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 45\n'
        "[traffic]\nvehicles = 8\nwindow_radius_m = 80.0\nspawn_min_distance_m = 50.0\n"
        "[render]\nvisibility = false\n"
        '[sensor]\npreset = "perfect"\n'
        "[sensor.detection]\nprobability = 1.0\nfull_range_m = 1000.0\nmax_range_m = 1001.0\n"
        "[sensor.box2d]\nrelative_sigma = 0.0\n"
        "[sensor.box3d]\ndepth_sigma_m = 0.0\ndepth_sigma_per_m = 0.0\nlateral_sigma_m = 0.0\nsize_sigma = 0.0\n"
        "yaw_sigma_deg = 0.0\nyaw_flip_probability = 0.0\nvelocity_sigma_mps = 0.0\n"
        "[sensor.score]\nsigma = 0.0\n"
        "[sensor.clutter]\nrate_per_frame = 0.0\n"
        "[sensor.embedding]\nsigma = 0.0\nocclusion_sigma = 0.0\n"
        '[[perturbations]]\nkind = "occlude"\nnearest = 1\nframes = [10, 29]\n'
    )
    run_pipeline(load_scenario(path), seed=2, tracker="sort", out=tmp_path / "run")
    result = explain(tmp_path / "run", metrics=["IDSW", "CLR_FN"], workers=1)
    document = result.document
    assert "occlude#0" in document["causes"] and document["mode"] == "exact"
    # scored per camera in 2D, another camera's detection of the actor is no duplicate: not a cause here
    assert "cross_camera" not in document["causes"] and "cross_camera" in document["null_causes"]
    for name in ("IDSW", "CLR_FN"):
        entry = document["metrics"][name]
        loss = entry["perfect"] - entry["actual"]
        assert loss < 0  # the occlusion costs identity switches and misses
        assert entry["shares"]["occlude#0"] / loss >= 0.9, (name, entry)


@pytest.mark.parametrize("arguments, message", [
    (["--causes", "occlusion,rain"], "--causes: unknown cause group 'rain'"),
    (["--metric", "HOTA,SPEED"], "--metric: 'SPEED' is not a metric of this run; 3D: AMOTA, "),
    (["--metric", "2d:AMOTA"], "--metric: '2d:AMOTA' is not a metric of this run; 3D: AMOTA, "),
])
def test_bad_cause_or_metric_is_one_line(run_folder, capsys, arguments, message):
    assert main(["explain", str(run_folder), *arguments]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"simrig: error: {message}") and err.count("\n") == 1
    assert err.endswith(" (see 'simrig explain --help')\n")  # an option's error says where options are described


def test_a_file_given_as_the_run_folder_is_called_a_file(tmp_path, capsys):
    (tmp_path / "my_scenario.toml").write_text('extends = "highway_surround6"\n')
    assert main(["explain", str(tmp_path / "my_scenario.toml")]) == 2
    err = capsys.readouterr().err
    assert "my_scenario.toml' is a file; give the folder of a 'simrig run'" in err and err.count("\n") == 1
    assert "--help" not in err  # not an option's error: no pointer to the options


def test_a_run_folder_without_tracks_is_one_line(tmp_path, run_folder, capsys):
    import shutil

    shutil.copytree(run_folder / "dataset", tmp_path / "run" / "dataset")
    assert main(["explain", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("simrig: error: ") and "no tracker run in this folder" in err and err.count("\n") == 1


@pytest.mark.parametrize("record, message", [
    (None, "tracker.json: missing, so the tracker of this run cannot be recreated"),
    ({"tracker": "no_such_tracker", "params": {}, "camera": None}, "the tracker cannot be recreated"),
    ({"tracker": "saga", "params": {"no_such_parameter": 1}, "camera": None}, "the tracker cannot be recreated"),
])
def test_a_tracker_that_cannot_be_recreated_is_one_line(tmp_path, run_folder, capsys, record, message):
    import shutil

    copy = tmp_path / "run"
    shutil.copytree(run_folder / "dataset", copy / "dataset")
    shutil.copytree(run_folder / "tracks", copy / "tracks")
    shutil.copytree(run_folder / "scores", copy / "scores")
    target = copy / "tracks" / "saga" / "tracker.json"
    if record is None:
        target.unlink()
    else:
        target.write_text(json.dumps(record))
    assert main(["explain", str(copy)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("simrig: error: ") and message in err and err.count("\n") == 1
    with pytest.raises(ExplainError):
        explain(copy)


def test_run_with_explain_adds_the_section_to_the_reports(tmp_path, capsys):
    """``simrig run ... --explain``: the run, then its explanation in scores/LABEL/report.md and report.md."""
    path = tmp_path / "quiet.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 15\n'
        "[traffic]\nvehicles = 8\nwindow_radius_m = 80.0\nspawn_min_distance_m = 50.0\n"
        "[render]\nvisibility = false\n"
        '[sensor]\npreset = "ideal_noise"\n'  # few cause groups (no ghosts, duplicates, confusion): exact
        "[sensor.detection]\nprobability = 1.0\n"
        "[sensor.clutter]\nrate_per_frame = 0.0\n"
        "[sensor.embedding]\nsigma = 0.0\nocclusion_sigma = 0.0\n"
    )
    out = tmp_path / "run"
    assert main(["run", str(path), "--tracker", "saga", "--out", str(out), "--explain", "--workers", "1",
                 "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "explain   saga on quiet, seed 0, 15 frames: exact Shapley values" in printed
    document = json.loads((out / "explain" / "saga" / "explain.json").read_text())
    section = (out / "scores" / "saga" / "report.md").read_text().split("### What each cause cost saga")[1]
    assert f"{document['metrics']['AMOTA']['actual']:.3f}" in section
    assert "### What each cause cost saga" in (out / "report.md").read_text()
    # a second run of the same tracker rewrites its report; the explanation is asked for again
    assert main(["run", str(path), "--tracker", "saga", "--out", str(out), "--quiet"]) == 0
    assert "What each cause cost" not in (out / "scores" / "saga" / "report.md").read_text()


def test_a_run_that_was_not_scored_is_one_line(tmp_path, run_folder, capsys):
    import shutil

    shutil.copytree(run_folder / "dataset", tmp_path / "run" / "dataset")
    shutil.copytree(run_folder / "tracks", tmp_path / "run" / "tracks")
    assert main(["explain", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("simrig: error: ") and "no errors.parquet" in err and err.count("\n") == 1


def test_a_rerun_stopped_before_its_end_leaves_no_finished_looking_explain(explained, monkeypatch, tmp_path):
    """The document is written last: stopped while drawing its figures, a rerun leaves no explain.json (an
    earlier one is removed first), so the folder does not look finished with mixed files."""
    import shutil

    import simrig.explain.api as api

    run = shutil.copytree(run_folder_of(explained), tmp_path / "run")
    out = run / explained.out.relative_to(run_folder_of(explained))
    assert (out / "explain.json").is_file()

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(api, "waterfall", interrupted)
    with pytest.raises(KeyboardInterrupt):
        explain(run, causes=["occlusion", "random_misses"], metrics=["AMOTA"], workers=1)
    assert (out / "verdicts.parquet").is_file() and not (out / "explain.json").exists()


def _synthetic_play(monkeypatch, game_value, players, tolerance, samples=None):
    """``play`` on a game whose coalition values are ``game_value(removed)``, with the coalitions it asks for."""
    import numpy as np

    from simrig.explain import api
    from simrig.explain.coalition import CoalitionResult

    asked = []

    def fake_tasks(tasks, engine, workers, address, progress=False):
        asked.extend(frozenset(task.removed) for task in tasks)
        return [(task, (CoalitionResult(task.removed, np.array([game_value(frozenset(task.removed))]), None),))
                for task in tasks]

    class Seeded:
        seed = 5
        path = "unused"

    monkeypatch.setattr(api, "run_tasks", fake_tasks)
    record = {"tracker": "sort", "params": {}, "camera": None}
    game = api.play(Seeded(), record, players, {"X": ("3d", "X")}, samples, None, tolerance=tolerance)
    return game, asked


def test_a_game_sampled_to_a_tolerance_stops_at_the_first_round_whose_intervals_are_within_it(monkeypatch):
    from simrig.explain.api import FIRST_ROUND
    from simrig.explain.shapley import sample_orders

    players = tuple("abcdefgh")  # more than are computed exactly
    weight = {p: i + 1.0 for i, p in enumerate(players)}
    additive, asked = _synthetic_play(monkeypatch, lambda removed: sum(weight[p] for p in removed), players, 0.05)
    # every marginal of an additive game is the player's weight: zero spread, so the first round is within it
    assert len(additive.orders) == FIRST_ROUND and additive.within(0.05) and additive.beyond(0.05) == []
    assert {p: float(additive.shares[p][0]) for p in players} == weight
    assert len(asked) == len(set(asked))  # no coalition run twice

    def interacting(removed):  # a pair of causes that only together cost anything, plus noise-like terms
        return 10.0 * ({"a", "b"} <= removed) + sum(((ord(p) % 7) - 3) * (len(removed) % 3) for p in removed)

    capped, asked = _synthetic_play(monkeypatch, interacting, players, 1e-9, samples=14)
    assert len(capped.orders) == 14 and not capped.within(1e-9)  # a tiny tolerance samples to the most allowed
    assert capped.orders == sample_orders(players, 14, 5)  # the rounds' orders (6, 10, 14) are --samples 14's
    assert len(asked) == len(set(asked))
    assert sum(float(capped.shares[p][0]) for p in players) == pytest.approx(interacting(frozenset(players))
                                                                           - interacting(frozenset()))
    assert capped.beyond(1e-9) == [0]  # the one metric, named in the table's head


@pytest.mark.parametrize(("arguments", "message"), [
    (["--tolerance", "0"], "--tolerance: a fraction in (0, 1] of each metric's scale, got 0"),
    (["--tolerance", "0.1", "--samples", "4"], "--tolerance needs --samples 6 or more"),
    (["--exact", "--samples", "4"], "--exact computes every coalition: it takes no --samples or --tolerance"),
])
def test_a_tolerance_or_exact_asked_for_wrongly_is_one_line(run_folder, capsys, arguments, message):
    assert main(["explain", str(run_folder), *arguments, "--quiet"]) != 0
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert err.endswith(" (see 'simrig explain --help')\n")
