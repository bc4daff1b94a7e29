"""Scenario validation: every bad input is one clear line naming the key and the file."""

import pytest
from simrig.scenarios import DEFAULT_SCENARIO, ScenarioError, catalog, load_scenario


def _write(tmp_path, text, name="mine.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_catalog_entries_are_valid_and_named_after_their_file():
    entries = catalog()
    assert {"highway_surround6", "highway_stereo"} <= set(entries)
    assert DEFAULT_SCENARIO in entries
    for name in entries:
        scenario = load_scenario(name)
        assert scenario.name == name
        assert scenario.description


def test_extends_overrides_only_what_it_changes(tmp_path):
    path = _write(tmp_path, 'extends = "highway_surround6"\n[traffic]\nvehicles = 12\n[rig]\noverlap_deg = 20.0\n')
    scenario = load_scenario(path)
    base = load_scenario("highway_surround6")
    assert scenario.name == "mine"
    assert scenario.traffic.vehicles == 12
    assert scenario.rig.overlap_deg == 20.0
    assert scenario.traffic.lanes == base.traffic.lanes
    assert scenario.traffic.class_mix == base.traffic.class_mix
    assert scenario.frame_rate_hz == base.frame_rate_hz


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ('name = "x"\n[traffic]\nvehiclez = 3\n', ["traffic.vehiclez", "unknown key"]),
        ('extends = "highway_surround6"\n[rig]\nfov = 3\n', ["rig.fov", "unknown key"]),
        ('extends = "highway_surround6"\nframes = -5\n', ["frames", "greater than or equal to 1"]),
        ('extends = "highway_surround6"\n[rig]\npreset = "fisheye"\n', ["rig.preset", "surround6"]),
        ('extends = "highway_surround6"\n[traffic]\nvehicles = "many"\n', ["traffic.vehicles", "integer"]),
        ('extends = "highway_stereo"\n[rig]\noverlap_deg = 5.0\n', ["rig.overlap_deg", "'stereo' preset"]),
        ('[traffic]\nenv = "roundabout-v0"\nlanes = 3\n', ["traffic.lanes", "only highway-v0"]),
        ('[traffic]\nwindow_radius_m = 50\nspawn_min_distance_m = 80\n', ["traffic.spawn_min_distance_m"]),
        ('[traffic]\nclass_mix = { car = 1, tank = 1 }\n', ["traffic.class_mix.tank"]),
        ('extends = "no_such_entry"\n', ["extends", "no_such_entry", "highway_surround6"]),
        ("frames = [\n", ["not valid TOML"]),
    ],
)
def test_bad_scenarios_give_one_line_naming_file_and_key(tmp_path, text, fragments):
    path = _write(tmp_path, text)
    with pytest.raises(ScenarioError) as raised:
        load_scenario(path)
    message = str(raised.value)
    assert "\n" not in message
    assert str(path) in message
    for fragment in fragments:
        assert fragment in message


def test_unknown_catalog_name_lists_the_catalog():
    with pytest.raises(ScenarioError, match="highway_surround6"):
        load_scenario("highway_surround7")


def test_extends_cycle_is_reported(tmp_path, monkeypatch):
    from simrig import scenarios

    _write(tmp_path, 'extends = "b"\n', "a.toml")
    _write(tmp_path, 'extends = "a"\n', "b.toml")
    monkeypatch.setattr(scenarios, "CATALOG_DIR", tmp_path)
    with pytest.raises(ScenarioError, match="cycle"):
        load_scenario(tmp_path / "a.toml")


@pytest.mark.parametrize("name", sorted(catalog()))
def test_every_catalog_scenario_is_read_back_from_its_manifest_record(name):
    # A dataset's manifest holds the resolved scenario (every field, defaults included); explain, the perf
    # cache and the bench read it back. The roundabout once failed here: its dump holds highway-v0's lane count.
    from simrig.scenarios.schema import scenario_from_record

    scenario = load_scenario(name)
    assert scenario_from_record(scenario.model_dump(mode="json")) == scenario
