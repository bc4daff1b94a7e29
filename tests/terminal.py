"""Start a CLI subprocess as a terminal would, for the tests that press Ctrl-C on it."""

from __future__ import annotations

import signal


def ctrl_c_delivered() -> None:
    """``preexec_fn``: the child reacts to SIGINT as when started from a terminal. A shell script that starts a
    job in the background (``cmd &`` without job control, as some CI runners do) makes SIGINT ignored, every
    descendant inherits that, and Python then never raises KeyboardInterrupt — the test would measure its
    launcher, not simrig."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
