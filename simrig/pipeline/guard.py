"""Running a tracker's code defensively: a time limit per call, and its output checked on return.

A tracker is the user's code. A call that does not return within the limit is stopped (``SIGALRM``, in the
main thread of a POSIX process: the CLI, a bench worker, a test) and reported as a timeout; an exception is
reported naming the tracker and the frame; what ``step()`` returns is checked before anything uses it
(a list of :class:`~simrig.types.Track`, integer ids unique in the frame, known labels, finite scores and
boxes, known cameras), so a bad value is an error naming tracker, frame, track and field — never a
traceback from deep inside Arrow or a silently converted number.

A call the alarm cannot stop — stuck inside C code that never returns to Python, or a tracker that ignores or
replaces ``SIGALRM`` — is ended by a watchdog thread a little later, with the whole process (one line on stderr);
outside the main thread no limit applies.
"""

from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from numbers import Integral, Real

import numpy as np

from simrig.errors import SimrigError
from simrig.types import ActorClass, Box2D, Box3D, Track

MAX_TRACKS_PER_FRAME = 10_000
"""The most tracks one frame's answer may hold (a real scene holds a few hundred objects at most)."""
MAX_TRACK_ID = 2**63 - 1
"""Track ids are stored as int64: 0 … this."""
FRAME_TIME_LIMIT_S = 60.0
"""[s] default limit on one ``step()`` call (``reset`` gets the same; ``finish`` this per frame stepped)."""
CLASS_NAMES = tuple(member.value for member in ActorClass)


class TrackerFault(SimrigError):
    """The tracker's own code failed: it raised, returned something that is not tracks, or ran too long."""


class TrackerTimeout(TrackerFault):
    """A tracker call did not return within its time limit."""


class _Expired(BaseException):
    """Raised inside the tracker's call by the alarm; a BaseException so that ``except Exception`` in the
    tracker does not swallow it."""


@contextmanager
def time_limit(seconds: float | None, what: str) -> Iterator[None]:
    """Stop the block with :class:`TrackerTimeout` (message ``what ... did not return within S s``) after
    ``seconds``; no limit when ``seconds`` is None or 0, or outside the main thread, or without ``setitimer``."""
    if not seconds or threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return

    def expired(signum, frame):
        raise _Expired

    previous = signal.signal(signal.SIGALRM, expired)
    _WATCHDOG.arm(seconds, what)
    try:
        signal.setitimer(signal.ITIMER_REAL, seconds)  # inside the try: a tiny limit may fire at once
        yield
    except _Expired:
        raise TrackerTimeout(f"{what} did not return within {seconds:g} s (the per-frame time limit); "
                             "it was stopped") from None
    finally:
        _WATCHDOG.disarm()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


WATCHDOG_GRACE_S = 2.0
"""[s] the least time the watchdog gives a call past its limit to be stopped by the alarm (also half the limit)."""
WATCHDOG_EXIT_CODE = 124
"""Exit status of a process the watchdog ends (``timeout``'s)."""


class _Watchdog:
    """The second stop of :func:`time_limit`: a daemon thread that ends the process (one line on stderr, exit
    status :data:`WATCHDOG_EXIT_CODE`) when a call is still running :data:`WATCHDOG_GRACE_S` (or half its limit)
    after its limit — the alarm did not stop it, because the tracker ignores or replaced ``SIGALRM``, cancelled
    the timer, or is stuck in C code. Nothing else can stop a call in this process; an interactive command would
    otherwise hang for good, and a bench worker's death is reported by the bench."""

    def __init__(self):
        self._condition = threading.Condition()
        self._deadline: float | None = None
        self._what = ""
        self._thread: threading.Thread | None = None

    def arm(self, seconds: float, what: str) -> None:
        with self._condition:
            self._deadline = time.monotonic() + seconds + max(WATCHDOG_GRACE_S, seconds / 2)
            self._what, self._limit = what, seconds
            if self._thread is None or not self._thread.is_alive():  # one per process (a fork has none)
                self._thread = threading.Thread(target=self._watch, name="simrig-watchdog", daemon=True)
                self._thread.start()
            self._condition.notify()

    def disarm(self) -> None:
        with self._condition:
            self._deadline = None
            self._condition.notify()

    def _watch(self) -> None:
        with self._condition:
            while True:
                if self._deadline is None:
                    self._condition.wait()
                    continue
                left = self._deadline - time.monotonic()
                if left > 0:
                    self._condition.wait(left)
                    continue
                sys.stderr.write(f"simrig: error: {self._what} did not return within {self._limit:g} s and could "
                                 "not be stopped (it ignores or replaced SIGALRM, cancelled the timer, or is stuck "
                                 "in C code): the process ends here\n")
                sys.stderr.flush()
                _exit_now(WATCHDOG_EXIT_CODE)


_WATCHDOG = _Watchdog()


def _exit_now(code: int) -> None:
    """End the process at once: the C ``_exit`` itself (``posix._exit``), since ``os._exit`` is replaced while a
    tracker runs (:mod:`simrig.pipeline.track` refuses a tracker's own call)."""
    try:
        import posix
    except ImportError:  # pragma: no cover - not a POSIX system: no alarm, no watchdog either
        os._exit(code)
    posix._exit(code)


def _finite_box(box, kind: type, where: str, field: str) -> None:
    if not isinstance(box, kind):
        raise TrackerFault(f"{where}: {field} is a {type(box).__name__}, not a {kind.__name__}")
    values = box.as_array()
    if not np.all(np.isfinite(values)):
        raise TrackerFault(f"{where}: {field} has a non-finite value ({values.tolist()})")


def checked_tracks(returned: object, *, tracker: str, frame: int, cameras: tuple[str, ...],
                   call: str = "step()") -> list[Track]:
    """``returned`` (what one ``step()`` gave for ``frame``) as a list of valid tracks, or a
    :class:`TrackerFault` naming ``tracker``, the frame, the track and the field."""
    where = f"tracker {tracker!r}: frame {frame}"
    if not isinstance(returned, (list, tuple)):
        raise TrackerFault(f"{where}: {call} returned a {type(returned).__name__}, not a list of Track")
    if len(returned) > MAX_TRACKS_PER_FRAME:
        raise TrackerFault(f"{where}: {call} returned {len(returned):,} tracks, more than the {MAX_TRACKS_PER_FRAME:,} "
                           "a frame may hold")
    seen: set[int] = set()
    for index, track in enumerate(returned):
        if not isinstance(track, Track):
            raise TrackerFault(f"{where}: item {index} is a {type(track).__name__}, not a Track")
        track_id = track.track_id
        if isinstance(track_id, bool) or not isinstance(track_id, Integral):
            raise TrackerFault(f"{where}: item {index}: track_id {track_id!r} is not an integer")
        if not 0 <= int(track_id) <= MAX_TRACK_ID:
            raise TrackerFault(f"{where}: item {index}: track_id {int(track_id)} is outside 0 … 2⁶³ − 1")
        place = f"{where}: track {int(track_id)}"
        if int(track_id) in seen:
            raise TrackerFault(f"{place}: track_id appears twice in this frame")
        seen.add(int(track_id))
        if not isinstance(track.label, str) or track.label not in CLASS_NAMES:
            raise TrackerFault(f"{place}: label {track.label!r} is not a known class ({', '.join(CLASS_NAMES)})")
        score = track.score
        if isinstance(score, bool) or not isinstance(score, Real) or not math.isfinite(score):
            raise TrackerFault(f"{place}: score {score!r} is not a finite number")
        if not 0.0 <= score <= 1.0:
            raise TrackerFault(f"{place}: score {score!r} is outside 0 … 1 (a confidence)")
        if track.box3d is not None:
            _finite_box(track.box3d, Box3D, place, "box3d")
        if not isinstance(track.boxes2d, Mapping):
            raise TrackerFault(f"{place}: boxes2d is a {type(track.boxes2d).__name__}, not a mapping camera → Box2D")
        for camera, box in track.boxes2d.items():
            if camera not in cameras:
                raise TrackerFault(f"{place}: boxes2d names camera {camera!r}, not one of the rig's "
                                   f"({', '.join(cameras)})")
            _finite_box(box, Box2D, place, f"boxes2d[{camera!r}]")
    return list(returned)
