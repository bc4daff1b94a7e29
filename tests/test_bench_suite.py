"""Suites: validation errors that name the file and the entry, sweeps by path or alias, the plan's points
and cells counted by hand."""

import pytest
from simrig.scenarios import ScenarioError, load_scenario
from simrig.scenarios.overrides import get_setting, with_setting

from simrig.benchmark.parameters import apply_parameter, parameter_value
from simrig.benchmark.plan import BASE, make_plan
from simrig.benchmark.suite import SuiteError, load_suite, suite_catalog


def _suite(tmp_path, text: str, name: str = "mine"):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


MINIMAL = 'scenarios = ["highway_surround6"]\nseeds = [0]\n[[trackers]]\ntracker = "saga"\n'


def test_named_suites_load():
    assert {"smoke", "standard"} <= set(suite_catalog())
    for name in suite_catalog():
        suite, scenarios = load_suite(name)
        assert suite.name == name and scenarios


def test_standard_covers_every_catalog_scenario_and_reference_tracker():
    from simrig.scenarios import catalog
    from simrig.trackers import DEGRADERS, TRAINED_ON_SIMRIG, registry

    suite, _ = load_suite("standard")
    assert set(suite.scenarios) == set(catalog())
    not_references = set(TRAINED_ON_SIMRIG) | set(DEGRADERS)
    assert {entry.tracker for entry in suite.trackers} == set(registry.available()) - not_references
    learned, _ = load_suite("learned")  # a tracker trained on simrig data has a suite of its own
    assert set(TRAINED_ON_SIMRIG) <= {entry.tracker for entry in learned.trackers}
    assert {sweep.parameter for sweep in suite.sweeps} == {"miss_probability", "rig.overlap_deg"}
    assert len(suite.seeds) == 3


@pytest.mark.parametrize(("text", "expected"), [
    ("colour = 1\n" + MINIMAL, "': colour: unknown key"),
    (MINIMAL + "colour = 1\n", "trackers.0.colour: unknown key"),
    (MINIMAL.replace("highway_surround6", "nowhere"), "scenarios.0: unknown scenario 'nowhere'"),
    (MINIMAL + "[trackers.params]\nbogus = 1\n", "trackers.0 (saga"),
    (MINIMAL.replace("seeds = [0]", "seeds = [0, 0]"), "seeds: 0 is listed twice"),
    (MINIMAL + '[[trackers]]\ntracker = "saga"\n', "trackers: 'saga' is listed twice"),
    (MINIMAL + '[[trackers]]\ntracker = "sort"\ncamera = "left"\n', "camera 'left' is not in the rig of"),
    (MINIMAL + '[[trackers]]\ntracker = "sort"\nrigs = ["stereo"]\n', "match none of the suite's scenarios"),
    (MINIMAL + '[[sweeps]]\nparameter = "miss_probability"\nvalues = [1.5]\n',
     "sweeps.0 (miss_probability) on highway_surround6"),
    (MINIMAL + '[[sweeps]]\nparameter = "rig.overlap_deg"\nvalues = [10]\nscenarios = ["highway_stereo"]\n',
     "sweeps.0.scenarios: 'highway_stereo' is not one of the suite's scenarios"),
    (MINIMAL + '[[sweeps]]\nparameter = "density"\nvalues = [10]\n', "sweeps.0.parameter: 'density' is neither"),
    (MINIMAL + '[[sweeps]]\nparameter = "traffic.vehicle"\nvalues = [10]\n', "has no key 'vehicle'"),
    ('base = false\n' + MINIMAL, "base: with base = false the suite needs at least one sweep"),
])
def test_invalid_suites_name_file_and_entry(tmp_path, text, expected):
    path = _suite(tmp_path, text)
    with pytest.raises(SuiteError) as error:
        load_suite(path)
    assert str(path) in str(error.value)
    assert expected in str(error.value)


def test_a_sweep_that_does_not_fit_a_preset_says_how_to_limit_it(tmp_path):
    path = _suite(tmp_path, MINIMAL.replace('["highway_surround6"]', '["highway_surround6", "highway_stereo"]')
                  + '[[sweeps]]\nparameter = "rig.overlap_deg"\nvalues = [20]\n')
    with pytest.raises(SuiteError, match=r"on highway_stereo: .*not a setting of the 'stereo' preset.*scenarios = "):
        load_suite(path)


def test_unknown_suite_lists_named_ones():
    with pytest.raises(SuiteError, match="not a named suite \\(.*smoke.*\\)"):
        load_suite("nonexistent")


def test_settings_by_path_and_alias():
    scenario = load_scenario("burst_misses")
    assert get_setting(scenario, "perturbations.0.frames") == (50, 79)
    assert with_setting(scenario, "perturbations.0.frames.1", 60).perturbations[0].frames == (50, 60)
    assert with_setting(scenario, "traffic.vehicles", 7).traffic.vehicles == 7
    assert scenario.traffic.vehicles == 25  # the original is untouched
    assert parameter_value(scenario, "miss_probability") == pytest.approx(0.1)
    assert apply_parameter(scenario, "miss_probability", 0.3).sensor.detection.probability == 0.7
    assert isinstance(apply_parameter(scenario, "traffic.vehicles", 12.0).traffic.vehicles, int)
    with pytest.raises(ScenarioError, match="vehicles"):
        apply_parameter(scenario, "traffic.vehicles", -1)
    with pytest.raises(ScenarioError, match="has no item 5"):
        get_setting(scenario, "perturbations.5.frames")


def test_setting_the_preset_replaces_the_detector():
    scenario = load_scenario("highway_surround6")
    assert scenario.sensor.preset == "bevformer_small" and scenario.sensor.ghosts.birth_rate_hz > 0
    ideal = with_setting(scenario, "sensor.preset", "ideal_noise")
    assert ideal.sensor == load_scenario("highway_surround6").sensor.model_validate({"preset": "ideal_noise"})
    assert ideal.sensor.ghosts.birth_rate_hz == 0.0  # not the old preset's ghosts under the new name
    assert with_setting(ideal, "sensor.detection.probability", 0.5).sensor.detection.probability == 0.5


def test_smoke_plan_counted_by_hand():
    suite, scenarios = load_suite("smoke")
    plan = make_plan(suite, scenarios)
    # per seed: highway_surround6 base + 2 miss + 2 overlap = 5 points, stereo_occluder base + 2 miss = 3
    assert len(plan.points) == 2 * (5 + 3)
    # the miss value 0.1 and the overlap 10 are the scenarios' own: the base cell again
    assert len(plan.cells) == 2 * (3 + 2)
    for point in plan.points:
        if point.sweep in ("miss_probability", "rig.overlap_deg") and point.value in (0.1, 10.0):
            base = next(p for p in plan.points if p.sweep == BASE and p.scenario == point.scenario
                        and p.seed == point.seed)
            assert point.cell == base.cell
    stereo = [p for p in plan.points if p.scenario == "stereo_occluder"]
    assert all(dict(p.settings)["rig.overlap_deg"] is None for p in stereo)  # not swept there: no value
    # collabmot runs on the stereo cells only: 6 surround cells × 2 trackers + 4 stereo cells × 3
    assert sum(len(pairs) for pairs in plan.work().values()) == 6 * 2 + 4 * 3
