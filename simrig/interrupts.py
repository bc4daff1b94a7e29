"""Ctrl-C that a library swallowed still stops simrig.

The command line notes every SIGINT here (:func:`noting_interrupts`) before raising ``KeyboardInterrupt`` as
Python would. A library that catches it (a bare ``except:`` around an optional import, say) would let a long
loop run on to the end; the loops that take long (one generated frame, one tracked frame) call
:func:`stop_if_interrupted`, which raises it again. Outside the command line nothing is installed and the check
costs one attribute read.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_state = {"interrupted": False}


def interrupted() -> bool:
    """Whether Ctrl-C arrived since :func:`noting_interrupts` began."""
    return _state["interrupted"]


def stop_if_interrupted() -> None:
    """Raise ``KeyboardInterrupt`` when Ctrl-C arrived and was swallowed on its way up."""
    if _state["interrupted"]:
        raise KeyboardInterrupt


@contextmanager
def noting_interrupts() -> Iterator[None]:
    """Note SIGINT (in the main thread, when Python's default handler is in place) for the block, raising
    ``KeyboardInterrupt`` as usual; the previous handler is restored after."""
    previous = signal.getsignal(signal.SIGINT)
    install = previous is signal.default_int_handler and threading.current_thread() is threading.main_thread()

    def note(signum, frame):
        _state["interrupted"] = True
        raise KeyboardInterrupt

    _state["interrupted"] = False
    if install:
        signal.signal(signal.SIGINT, note)
    try:
        yield
    finally:
        if install:
            signal.signal(signal.SIGINT, previous)
        _state["interrupted"] = False
