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
