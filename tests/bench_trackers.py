"""Trackers for the bench tests, importable by spawned pool workers as ``bench_trackers:NAME``."""


class Crashing:
    """Fails on its first frame, the way a user's buggy tracker would."""

    def reset(self, rig, seed):
        pass

    def step(self, frame):
        raise RuntimeError("this tracker always fails")
