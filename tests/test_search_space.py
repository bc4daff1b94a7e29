"""Search spaces: the catalog loads, bad input is one line naming the key and the file, data files run no code."""

from __future__ import annotations

from pathlib import Path

import pytest

from simrig.cli import main
from simrig.search import SearchError, load_space
from simrig.search.space import setting_value

GOOD = """
name = "tiny"
base = "highway_surround6"
frames = 20
tracker = "saga"
budget = 3
seeds = 1

[base_settings]
"render.visibility" = false
"perturbations" = [{ kind = "occlude", nearest = 1, frames = [2, 4] }]

[objective]
metric = "2d_IDF1"
direction = "minimize"
failure = { metric = "3d_IDS", at_least = 1 }

[[dimensions]]
path = "perturbations.0.frames"
start = [0, 5]
length = [1, 10]

[[dimensions]]
path = "sensor.detection.probability"
low = 0.5
high = 1.0
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "space.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_catalog_space_loads_and_sets_every_dimension():
    space = load_space("occlusion_gaps")
    assert space.config.objective.failure_metric == "2d_IDSW"  # every tracker, 2D or 3D, reports it
    candidate = {"perturbations.0.frames.start": 4, "perturbations.0.frames.length": 6,
                 "perturbations.0.nearest": 2, "perturbations.1.frames.start": 30,
                 "perturbations.1.frames.length": 8, "perturbations.1.probability": 0.25}
    scenario = space.scenario_for(candidate)
    occlude, burst = scenario.perturbations
    assert (occlude.frames, occlude.nearest) == ((4, 9), 2)  # [start, start + length - 1]
    assert (burst.frames, burst.probability) == ((30, 37), 0.25)
    assert scenario.frames == 40 and scenario.traffic.vehicles == 4 and not scenario.render.visibility


def test_a_window_value_is_start_to_start_plus_length_minus_one():
    dimension = load_space("occlusion_gaps").config.dimensions[0]
    assert setting_value(dimension, {f"{dimension.path}.start": 7, f"{dimension.path}.length": 1}) == [7, 7]


@pytest.mark.parametrize(("change", "expected"), [
    (('path = "sensor.detection.probability"', 'path = "sensor.detection.nonsense"'),
     "dimensions.1.path (sensor.detection.nonsense): setting 'sensor.detection.nonsense'"),
    (("low = 0.5\nhigh = 1.0", "low = 0.9\nhigh = 0.2"),
     "dimensions.1 (sensor.detection.probability).high: the range [0.9, 0.2] is empty"),
    (("length = [1, 10]", "length = [6, 3]"),
     "dimensions.0 (perturbations.0.frames).length: the range [6, 3] is empty"),
    (("budget = 3", "budget = 0"), "budget: Input should be greater than or equal to 1"),
    (('metric = "2d_IDF1"', 'metric = "2d_FUN"'), "objective.metric: '2d_FUN' is not a metric the scorer reports"),
    (('metric = "3d_IDS"', 'metric = "IDs"'), "objective.failure.metric: 'IDs' is not a metric the scorer"),
    (("seeds = 1", "seeds = 1\ncolour = 3"), "colour: unknown key"),
    (("length = [1, 10]", "length = [1, 20]"), "dimensions.0.length: the window can end at frame 24, past the last"),
    (('tracker = "saga"', 'tracker = "nosuch"'), "tracker: unknown tracker 'nosuch'"),
    (("high = 1.0", "high = 1.5"), "dimensions.1.path (sensor.detection.probability): scenario 'highway_surround6'"),
])
def test_bad_input_is_one_line_naming_the_key_and_the_file(tmp_path, change, expected):
    old, new = change
    assert old in GOOD
    path = _write(tmp_path, GOOD.replace(old, new))
    with pytest.raises(SearchError) as caught:
        load_space(path)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"search space file {str(path)!r}: ")
    assert expected in message


def test_the_command_line_prints_one_line_and_exits_2(tmp_path, capsys):
    path = _write(tmp_path, GOOD.replace("budget = 3", "budget = 0"))
    assert main(["search", str(path), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and error.startswith("simrig: error: search space file") and "budget" in error
    assert main(["search", "no_such_space"]) == 2
    assert "unknown search space 'no_such_space'" in capsys.readouterr().err


def test_a_tracker_to_import_in_a_data_file_is_refused_unless_allowed(tmp_path, monkeypatch):
    module = tmp_path / "planted_tracker_module.py"
    module.write_text("import pathlib\npathlib.Path(__file__).with_name('imported').write_text('yes')\n"
                      "from simrig.trackers.sort import sort as factory\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    path = _write(tmp_path, GOOD.replace('tracker = "saga"', 'tracker = "planted_tracker_module:factory"'))
    with pytest.raises(SearchError, match="is a module:attribute reference, and a data file may only name registered"):
        load_space(path)
    assert not (tmp_path / "imported").exists()  # refused before anything was imported
    assert load_space(path, trust_file=True).tracker == "planted_tracker_module:factory"
    assert (tmp_path / "imported").exists()


def test_every_value_of_every_dimension_falls_in_exactly_one_coverage_bin():
    import numpy as np

    from simrig.search.coverage import bins

    for dimension in load_space("occlusion_gaps").config.dimensions:
        for name in dimension.names:
            if dimension.kind == "window":
                low, high = dimension.start if name.endswith(".start") else dimension.length
                values = range(low, high + 1)
            elif dimension.integer:
                values = range(dimension.low, dimension.high + 1)
            else:
                values = np.linspace(dimension.low, dimension.high, 101)
            tests = [inside for _, inside in bins(dimension, name)]
            assert all(sum(inside(v) for inside in tests) == 1 for v in values), name
