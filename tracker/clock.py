"""The time step between consecutive frames [s], checked."""

from __future__ import annotations

from simrig.types import SensorFrame

from .errors import TrackerInputError


class FrameClock:
    """Remembers the last frame's timestamp; ``advance(frame)`` returns Δt [s] (0 for the first frame) and
    rejects a timestamp that does not move forward, naming both frames."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self._time: float | None = None
        self._frame: int | None = None

    def advance(self, frame: SensorFrame) -> float:
        if self._time is not None and not frame.timestamp > self._time:
            raise TrackerInputError(
                f"frame {frame.frame}: timestamp {frame.timestamp} s is not after the previous frame's "
                f"({self._frame}: {self._time} s); call reset() between sequences"
            )
        dt = 0.0 if self._time is None else frame.timestamp - self._time
        self._time, self._frame = frame.timestamp, frame.frame
        return dt
