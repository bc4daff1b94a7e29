"""``simrig bench --explain``: every tracker explained on every base cell, and the report's "What each cause
costs" section made of it."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from simrig.benchmark import run_bench
from simrig.cli import main
from simrig.explain.bench import explain_bench
from simrig.report import write_report
from simrig.report.cause_costs import cause_costs_section

SCENARIO = """extends = "highway_surround6"
frames = 15
[traffic]
vehicles = 12
window_radius_m = 100.0
spawn_min_distance_m = 70.0
[render]
visibility = false
[sensor.detection]
probability = 0.8
"""
SUITE = """name = "tinyexplain"
scenarios = ["tiny_scenario.toml"]
seeds = [0]
[[trackers]]
tracker = "saga"
[[trackers]]
tracker = "sort"
[[sweeps]]
parameter = "miss_probability"
values = [0.4]
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    folder = tmp_path_factory.mktemp("suite")
    (folder / "tiny_scenario.toml").write_text(SCENARIO)
    (folder / "tiny.toml").write_text(SUITE)
    run = run_bench(folder / "tiny.toml", out=folder / "bench", workers=1)
    explain_bench(run.out, samples=2, workers=1)
    return run


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_every_tracker_on_every_base_cell_has_shares_that_add_up(bench):
    rows = pq.read_table(bench.out / "explain.parquet").to_pandas()
    assert set(rows["tracker"]) == {"saga", "sort"}
    assert set(rows.loc[rows["tracker"] == "saga", "metric"]) == {"AMOTA", "HOTA", "IDS", "FN", "FRAG"}
    assert set(rows.loc[rows["tracker"] == "sort", "metric"]) == {"HOTA", "IDSW", "CLR_FN", "Frag"}  # a 2D tracker
    results = pq.read_table(bench.results).to_pandas()
    assert set(rows["cell"]) == set(results.loc[results["sweep"] == "", "cell"])  # base cells only
    for (_, _), group in rows.groupby(["tracker", "metric"]):
        first = group.iloc[0]
        assert group["share"].sum() == pytest.approx(first["perfect"] - first["actual"], abs=1e-9)
    hota = results[(results["sweep"] == "") & (results["tracker"] == "saga")]["2d_HOTA"].iloc[0]
    assert rows[(rows["tracker"] == "saga") & (rows["metric"] == "HOTA")]["actual"].iloc[0] == pytest.approx(hota)


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_the_report_section_says_what_each_cause_costs_each_tracker(bench):
    section = "\n".join(cause_costs_section(bench.out, "tinyexplain"))
    rows = pq.read_table(bench.out / "explain.parquet").to_pandas()
    for tracker in ("saga", "sort"):
        assert f"### {tracker}" in section
        mine = rows[(rows["tracker"] == tracker) & (rows["metric"] == "HOTA")]
        worst = mine.loc[mine["share"].idxmax()]
        assert f"`{tracker}` loses most of its HOTA to {worst['cause'].replace('_', ' ')} ({worst['share']:+.3f}" \
            in section
    assert section.startswith("## What each cause costs")
    ordered = "\n".join(cause_costs_section(bench.out, "tinyexplain", ["sort", "saga"]))  # the suite's order
    assert ordered.index("### sort") < ordered.index("### saga")


def test_the_section_means_count_an_absent_group_as_zero_and_sum_scheduled_windows_per_kind(tmp_path):
    import pyarrow as pa

    from simrig.explain.bench import SCHEMA

    def row(cell, cause, share, actual, perfect):
        return {"scenario": cell, "seed": 0, "cell": cell, "tracker": "t", "metric": "HOTA", "cause": cause,
                "share": share, "ci95": None, "actual": actual, "perfect": perfect, "mode": "exact"}

    rows = [row("a", "occlusion", 0.1, 0.5, 0.7), row("a", "occlude#0", 0.06, 0.5, 0.7),
            row("a", "occlude#1", 0.04, 0.5, 0.7), row("b", "occlusion", 0.3, 0.4, 0.7)]
    table = pa.Table.from_pylist(rows, schema=SCHEMA.with_metadata({"command": "simrig bench x --explain"}))
    pq.write_table(table, tmp_path / "explain.parquet")
    section = "\n".join(cause_costs_section(tmp_path, "x"))
    # occlusion: (0.1 + 0.3) / 2; the two windows of cell a are one kind, absent from b: (0.06 + 0.04 + 0) / 2;
    # together the mean gap ((0.7 - 0.5) + (0.7 - 0.4)) / 2 = 0.25
    assert "| occlusion | +0.200 |" in section and "| occlude (scheduled) | +0.050 |" in section
    assert "| actual | 0.450 |" in section and "(+0.200 of a 0.250 gap)" in section
    assert "Produced by `simrig bench x --explain`." in section


def test_a_bench_without_explanation_says_how_to_get_one(tmp_path):
    section = "\n".join(cause_costs_section(tmp_path, "tinyexplain"))
    assert "Not computed for this bench: `simrig bench tinyexplain --explain`" in section


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_cell_explained_with_the_other_trackers_equals_each_tracker_explained_alone(bench, tmp_path):
    # The bench runs each (cell, coalition) once for every tracker that needs it; the shares must be those of
    # explaining each tracker on its own (simrig explain's game).
    import json

    from simrig.scenarios.schema import scenario_from_record

    from simrig.dataset import Dataset
    from simrig.explain.api import choose_metrics, play
    from simrig.sensor.groups import present_groups

    rows = pq.read_table(bench.out / "explain.parquet").to_pandas()
    cache = json.loads((bench.out / "bench.json").read_text())["cache"]
    for tracker, in_3d in (("saga", True), ("sort", False)):
        mine = rows[rows["tracker"] == tracker]
        dataset = Dataset.open(f"{cache}/{mine['cell'].iloc[0]}")
        players = present_groups(scenario_from_record(dataset.scenario), len(dataset.rig.cameras), scored_in_3d=in_3d)
        chosen = choose_metrics(None, in_3d)
        alone = play(dataset, {"tracker": tracker, "params": {}, "camera": None}, players, chosen, 2,
                     tmp_path / tracker, workers=1).metrics(chosen)
        for metric, values in alone.items():
            shares = mine[mine["metric"] == metric].set_index("cause")["share"]
            assert shares.to_dict() == pytest.approx(values["shares"], abs=1e-12)
            assert len(shares) == len(players) >= 5


@pytest.mark.slow
def test_the_bench_report_has_the_section_and_keeps_its_table(bench, tmp_path):
    text = write_report(bench.out, out=tmp_path / "report").read_text()
    assert "## What each cause costs" in text and "`saga` loses most of its HOTA to" in text
    assert (tmp_path / "report" / "explain.parquet").is_file()  # the report folder can be made again


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_explaining_only_some_seeds(bench, tmp_path, capsys):
    import shutil

    copy = tmp_path / "bench"
    shutil.copytree(bench.out, copy)
    explain_bench(copy, samples=2, workers=1, seeds=[0])  # the cache is warm: only bookkeeping runs
    assert set(pq.read_table(copy / "explain.parquet").column("seed").to_pylist()) == {0}
    assert "(1 cell: 1 scenario × seed 0)" in "\n".join(cause_costs_section(copy, "tinyexplain"))
    from simrig.explain import ExplainError

    with pytest.raises(ExplainError, match=r"--explain-seeds: 5 not a seed of this bench \(its seeds: 0\)"):
        explain_bench(copy, seeds=[5])
    with pytest.raises(SystemExit):
        main(["bench", "tinyexplain", "--explain", "--explain-seeds", "a"])
    assert "--explain-seeds: expected seeds separated by commas" in capsys.readouterr().err


def test_explaining_an_unfinished_bench_is_one_line(tmp_path, capsys):
    from simrig.explain import ExplainError

    with pytest.raises(ExplainError, match="not a finished bench folder"):
        explain_bench(tmp_path)
    assert main(["bench", "no_such_suite", "--explain", "--out", str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_tracker_that_times_out_in_the_bench_is_left_out_and_the_others_are_explained(tmp_path, monkeypatch,
                                                                                           capsys):
    # A hanging tracker: the bench records its timeout; --explain used to run it again on every
    # counterfactual and stopped the whole explanation at its first timeout.
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    monkeypatch.setenv("PYTHONPATH", str(Path(__file__).parent))  # for spawned workers
    (tmp_path / "tiny_scenario.toml").write_text(SCENARIO)
    (tmp_path / "hang.toml").write_text(
        'name = "hang"\nscenarios = ["tiny_scenario.toml"]\nseeds = [0]\nframes = 8\nframe_time_limit_s = 2\n'
        '[[trackers]]\ntracker = "saga"\n[[trackers]]\ntracker = "bench_trackers:HangsOnFrame3"\n')
    out = tmp_path / "bench"
    assert main(["bench", str(tmp_path / "hang.toml"), "--out", str(out), "--workers", "1", "--quiet", "--trust-file",
                 "--explain", "--explain-samples", "2"]) == 0
    printed = capsys.readouterr().out
    assert "explain   not explained: bench_trackers:HangsOnFrame3 on cell " in printed
    assert "it failed in the bench: timeout: tracker 'bench_trackers:HangsOnFrame3': frame 3: step() did not" \
        in printed
    rows = pq.read_table(out / "explain.parquet").to_pandas()
    assert set(rows["tracker"]) == {"saga"} and len(rows) > 0
    section = "\n".join(cause_costs_section(out, "hang"))
    assert "Not explained (left out of the means below):" in section
    assert "- `bench_trackers:HangsOnFrame3` on cell `" in section and "### saga" in section


@pytest.mark.slow  # an end-to-end run: the default pass is kept near 5 minutes, CI's slow pass runs it
def test_a_tracker_failing_on_one_counterfactual_is_left_out_of_the_bench_explanation(bench, tmp_path, monkeypatch):
    import shutil

    from simrig.explain import coalition
    from simrig.pipeline.guard import TrackerFault

    real = coalition.run_tracker

    def sort_fails_on_counterfactuals(dataset, name, out, params, **kwargs):
        if name == "sort" and "/explain-cache/" in str(dataset.path):  # counterfactuals only
            raise TrackerFault("tracker 'sort': frame 4: step() raised ValueError: planted")
        return real(dataset, name, out, params, **kwargs)

    monkeypatch.setattr(coalition, "run_tracker", sort_fails_on_counterfactuals)
    copy = tmp_path / "bench"
    shutil.copytree(bench.out, copy)
    explain_bench(copy, samples=2, workers=1)  # in this process: the patched tracker runs
    table = pq.read_table(copy / "explain.parquet")
    assert set(table.column("tracker").to_pylist()) == {"saga"}  # saga's game is whole, sort's is not
    from simrig.explain.bench import not_explained

    (entry,) = not_explained(table.schema)
    assert entry["tracker"] == "sort" and entry["reason"].startswith("on the counterfactual without ")
    assert entry["reason"].endswith(": tracker 'sort': frame 4: step() raised ValueError: planted")


def test_simrig_explain_names_the_counterfactual_its_tracker_failed_on(tmp_path):
    import numpy as np

    from simrig.explain.api import failed_coalition
    from simrig.explain.coalition import CoalitionResult

    ok = CoalitionResult((), np.zeros(2), None)
    results = {frozenset(): ok, frozenset({"reid", "clutter"}): CoalitionResult(("clutter", "reid"), np.full(2, np.nan),
                                                                                None, "tracker 't': frame 2: boom"),
               frozenset({"occlusion"}): CoalitionResult(("occlusion",), np.full(2, np.nan), None, "tracker 't': x")}
    assert failed_coalition({frozenset(): ok}) is None
    assert failed_coalition(results) == "on the counterfactual without occlusion: tracker 't': x"  # smallest first


def test_explain_options_are_checked_before_the_bench_runs(tmp_path, capsys):
    # New-user trial: --explain-seeds 7 failed only after the whole bench had run; --explain-samples without
    # --explain was ignored.
    (tmp_path / "tiny_scenario.toml").write_text(SCENARIO)
    (tmp_path / "tiny.toml").write_text(SUITE)
    out = tmp_path / "bench"
    for extra, message in ((["--explain-samples", "2"], "simrig: error: --explain-samples needs --explain\n"),
                           (["--explain-seeds", "0", "--explain-samples", "2"],
                            "simrig: error: --explain-samples and --explain-seeds need --explain\n"),
                           (["--explain", "--explain-seeds", "0,7"],
                            "simrig: error: --explain-seeds: 7 not a seed of suite 'tinyexplain' (its seeds: 0)\n")):
        assert main(["bench", str(tmp_path / "tiny.toml"), "--out", str(out), "--quiet", *extra]) == 2
        assert capsys.readouterr().err == message
        assert not out.exists()  # nothing ran
