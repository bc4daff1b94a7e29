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
        ('[traffic]\nenv = "merge-v0"\nlayout = { kind = "ramps" }\n', ["traffic.layout", "env must be highway-v0"]),
        ('[traffic]\nlanes = 3\nlayout = { kind = "ramps" }\n', ["traffic.lanes", "not with a layout"]),
        ('[traffic]\nlayout = { kind = "spiral" }\n', ["traffic.layout", "'two_way', 'ramps', 'exits', 'crossings'"]),
        ('[traffic]\nlayout = { kind = "two_way", oncoming_share = 1.5 }\n', ["traffic.layout.two_way.oncoming_share"]),
        ('[traffic]\nlayout = { kind = "crossings", side_share = 0.7, oncoming_share = 0.5 }\n',
         ["traffic.layout.crossings", "side_share + oncoming_share: 0.7 + 0.5 exceeds 1"]),
        ('[traffic]\nlayout = { kind = "exits", ramp_share = 0.1 }\n',
         ["traffic.layout.exits.ramp_share", "unknown key"]),
        # a misspelt key or kind: the nearest name the table accepts is offered
        ('extends = "highway_surround6"\n[traffic]\nvehicels = 25\n',
         ["traffic.vehicels: unknown key (did you mean 'vehicles'?)"]),
        ('extends = "highway_surround6"\nframse = 5\n', ["framse: unknown key (did you mean 'frames'?)"]),
        ('extends = "highway_surround6"\n[[perturbations]]\nkind = "occlude"\nframes = [1, 5]\nactor = 3\n',
         ["perturbations.0.occlude.actor: unknown key (did you mean 'actors'?)"]),
        ('extends = "highway_surround6"\n[[perturbations]]\nkind = "ocllude"\nframes = [1, 5]\n',
         ["perturbations.0.kind: unknown kind 'ocllude' (did you mean 'occlude'?); known: 'occlude', 'miss_burst'"]),
        ('extends = "highway_surround6"\n[traffic]\nzebra = 1\n', ["traffic.zebra: unknown key"]),
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
    if "zebra" in text:  # nothing near it: no hint
        assert "did you mean" not in message


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


def test_a_layout_of_the_files_own_replaces_the_parents_road(tmp_path):
    # highway_surround6 sets lanes and ego_lane (highway-v0's); a layout replaces that road, so they are not inherited
    ramps = load_scenario(_write(tmp_path, 'extends = "highway_surround6"\n[traffic]\n'
                                           'layout = { kind = "ramps", lanes = 3 }\n', "ramps.toml"))
    assert ramps.traffic.layout.kind == "ramps" and ramps.traffic.layout.lanes == 3
    assert ramps.traffic.vehicles == load_scenario("highway_surround6").traffic.vehicles
    assert "lanes" not in ramps.model_dump(mode="json")["traffic"]
    # a layout of another kind replaces the parent's whole; one of the same kind merges key by key
    exits = load_scenario(_write(tmp_path, 'extends = "two_way_surround6"\n[traffic]\nlayout = { kind = "exits" }\n',
                                 "exits.toml"))
    assert exits.traffic.layout.kind == "exits" and exits.traffic.layout.exit_share == 0.3
    fewer = load_scenario(_write(tmp_path, 'extends = "two_way_surround6"\n[traffic.layout]\noncoming_share = 0.2\n',
                                 "fewer.toml"))
    assert fewer.traffic.layout.kind == "two_way" and fewer.traffic.layout.oncoming_share == 0.2
    # a lane count written on top of a layout is still refused
    with pytest.raises(ScenarioError, match=r"traffic.lanes: not with a layout"):
        load_scenario(_write(tmp_path, 'extends = "merge_surround6"\n[traffic]\nlanes = 3\n', "lanes.toml"))
