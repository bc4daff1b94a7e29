"""Trackers are found by name; unknown names and non-trackers are clear errors."""

import pytest

from simrig import trackers as tracker


class _Still:
    def reset(self, *, rig, seed=None):
        self.rig = rig

    def step(self, frame):
        return []


def test_registered_tracker_is_created_with_its_parameters():
    tracker.register("test-still", lambda gain=1.0: _Still())
    assert "test-still" in tracker.available()
    assert isinstance(tracker.create("test-still", gain=2.0), tracker.Tracker)


def test_unknown_name_lists_the_known_trackers():
    tracker.register("test-known", _Still)
    with pytest.raises(KeyError, match="unknown tracker 'nope'.*test-known"):
        tracker.create("nope")


def test_a_name_cannot_be_taken_twice_and_a_factory_must_build_a_tracker():
    tracker.register("test-twice", _Still)
    with pytest.raises(ValueError, match="already registered"):
        tracker.register("test-twice", lambda: _Still())
    tracker.register("test-bad", lambda: object())
    with pytest.raises(TypeError, match="no reset/step"):
        tracker.create("test-bad")


def test_registering_the_name_of_an_installed_packages_tracker_is_an_error_unless_replacing(monkeypatch):
    """A package's entry point (group ``simrig.trackers``) takes its name even before anything asked for the list
    of trackers: a later ``register`` of that name fails instead of shadowing it, unless it says ``replace``."""
    from importlib import metadata

    from simrig.trackers import registry

    installed = metadata.EntryPoint("test-installed", f"{__name__}:_Still", registry.ENTRY_POINT_GROUP)
    monkeypatch.setattr(registry.metadata, "entry_points",
                        lambda group: [installed] if group == registry.ENTRY_POINT_GROUP else [])
    with pytest.raises(ValueError, match="'test-installed' is already registered"):
        tracker.register("test-installed", lambda: _Still())
    tracker.register("test-installed", _Still)  # the factory the entry point names: no conflict
    replacement = lambda: _Still()  # noqa: E731
    tracker.register("test-installed", replacement, replace=True)
    assert registry._factory("test-installed") is replacement


def test_building_one_tracker_imports_no_other():
    """Trackers are imported when first asked for: a ``saga`` run pays for no other tracker's modules (nor what
    they import); listing the trackers imports none."""
    import subprocess
    import sys

    code = ("import sys\nfrom simrig.trackers import available, create\nnames = available()\n"
            "listed = sorted(m for m in sys.modules if m.startswith('simrig.trackers.'))\ncreate('saga')\n"
            "print(names)\nprint(listed)\nprint(sorted(m for m in sys.modules if m.startswith('simrig.trackers.')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    names, listed, after = (eval(line) for line in done.stdout.splitlines())  # noqa: S307  (our own printout)
    assert "saga" in names and "sort" in names
    assert listed == ["simrig.trackers.errors", "simrig.trackers.protocol", "simrig.trackers.registry"]
    others = {f"simrig.trackers.{name}" for name in names} - {"simrig.trackers.saga"}
    assert "simrig.trackers.saga" in after and not others & set(after)
