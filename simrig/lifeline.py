"""A pool worker's lifeline to its driver: it exits when the driver dies, however the driver died.

Kept to the standard library so that a freshly spawned worker reaches it (and starts watching) before it loads
the heavy parts of simrig: a worker spawned just before its driver was killed exits within a second or two.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time

PARENT_POLL_S = 0.5
"""[s] how often a pool worker checks that its driver is still alive."""
_PR_SET_PDEATHSIG = 1


def die_with(parent: int) -> None:
    """Pool worker initializer: ignore Ctrl-C (the driver handles it) and exit when process ``parent`` dies —
    at once through ``PR_SET_PDEATHSIG`` on Linux, and through a thread that watches the parent id anywhere."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:  # the driver died before the request took effect
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="simrig-parent-watch", daemon=True).start()
