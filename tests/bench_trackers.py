"""Trackers for the bench tests, importable by spawned pool workers as ``bench_trackers:NAME``."""


class Crashing:
    """Fails on its first frame, the way a user's buggy tracker would."""

    def reset(self, rig, seed):
        pass

    def step(self, frame):
        raise RuntimeError("this tracker always fails")


class HangsOnFrame3:
    """Tracks nothing, and never returns from its fourth ``step()`` (frame 3): a user's deadlocked tracker."""

    def reset(self, rig, seed):
        self.calls = 0

    def step(self, frame):
        self.calls += 1
        if self.calls == 4:
            import time

            while True:
                try:
                    time.sleep(3600)
                except Exception:  # noqa: S112 - a tracker that swallows errors must still be stopped
                    continue
        return []
