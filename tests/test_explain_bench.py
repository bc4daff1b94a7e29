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


def test_a_bench_without_explanation_says_how_to_get_one(tmp_path):
    section = "\n".join(cause_costs_section(tmp_path, "tinyexplain"))
    assert "Not computed for this bench: `simrig bench tinyexplain --explain`" in section


@pytest.mark.slow
def test_the_bench_report_has_the_section_and_keeps_its_table(bench, tmp_path):
    text = write_report(bench.out, out=tmp_path / "report").read_text()
    assert "## What each cause costs" in text and "`saga` loses most of its HOTA to" in text
    assert (tmp_path / "report" / "explain.parquet").is_file()  # the report folder can be made again


def test_explaining_an_unfinished_bench_is_one_line(tmp_path, capsys):
    from simrig.explain import ExplainError

    with pytest.raises(ExplainError, match="not a finished bench folder"):
        explain_bench(tmp_path)
    assert main(["bench", "no_such_suite", "--explain", "--out", str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
